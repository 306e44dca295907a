//! Running the `gonio` binary from the host's integration tests.

use gonio_firmware::config::REFERENCE;
use gonio_firmware::kinematics;
use gonio_shared::ScanSpec;
use std::collections::BTreeSet;
use std::process::{Command, Output};

/// The canonical indices of a grid scan's points the reference head can reach.
#[allow(dead_code)] // not every test binary that shares this module scans
pub fn reachable(spec: &ScanSpec) -> BTreeSet<u32> {
    (0..spec.len())
        .filter(|&i| spec.point(i).is_some_and(|g| kinematics::inverse(&REFERENCE, &g).is_ok()))
        .collect()
}

pub fn gonio(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_gonio"))
        .args(args)
        .output()
        .expect("running gonio")
}

/// Everything the command printed, stdout then stderr.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Checks a `report.html` written into `dir`: every link and picture it
/// names exists beside it, each model has its row with its fit and its BRDF
/// Explorer shader, and every θi has its pictures. Returns the HTML.
#[allow(dead_code)] // not every test binary that shares this module writes reports
pub fn check_report(dir: &std::path::Path, models: &[&str], theta_i: &[&str]) -> String {
    let html = std::fs::read_to_string(dir.join("report.html")).expect("report.html");
    let mut links = 0;
    for attr in ["href=\"", "src=\""] {
        for (at, _) in html.match_indices(attr) {
            let rest = &html[at + attr.len()..];
            let target = &rest[..rest.find('"').unwrap()];
            let path = dir.join(target);
            assert!(path.is_file(), "report links {target}, which is missing");
            assert!(std::fs::metadata(&path).unwrap().len() > 0, "{target} is empty");
            links += 1;
        }
    }
    for m in models {
        assert!(html.contains(&format!("<td class=\"l\">{m}</td>")), "row of {m}");
        assert!(html.contains(&format!("href=\"fits/{m}.brdf\"")) && html.contains(&format!("href=\"fits/{m}.json\"")));
    }
    for ti in theta_i {
        for kind in ["plane", "hemisphere", "residuals"] {
            assert!(
                html.contains(&format!("src=\"plots/{kind}-{ti}.png\"")),
                "{kind} picture of θi {ti}"
            );
        }
    }
    // The fits, the pictures per θi, and the R_A picture.
    assert_eq!(links, 2 * models.len() + 2 * 3 * theta_i.len() + 1, "links in the report");
    html
}
