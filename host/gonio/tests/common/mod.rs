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
    // One row per θi, holding that θi's pictures and no other's; the
    // retro-peak picture only where samples lie near the light.
    let mut pictures = 0;
    for ti in theta_i {
        let start = html
            .find(&format!("<h3>θi = {ti}°</h3>"))
            .unwrap_or_else(|| panic!("row of θi {ti}"));
        let row = &html[start..start + html[start..].find("</div>").unwrap()];
        for kind in ["plane", "cuts", "hemisphere", "residuals"] {
            assert!(
                row.contains(&format!("src=\"plots/{kind}-{ti}.png\"")),
                "{kind} picture in the row of θi {ti}"
            );
        }
        assert_eq!(
            row.matches(&format!("-{ti}.png\"")).count(),
            row.matches("<img").count(),
            "θi {ti}'s row"
        );
        pictures += row.matches("<img").count();
    }
    // The best fit for renderers, and Mitsuba's two pictures of it where
    // Mitsuba is installed (a note saying why not elsewhere).
    assert!(html.contains(".bsdf\">fits/"), "the best fit's .bsdf");
    let renders = html.matches("src=\"plots/render-").count();
    assert!(renders == 2 || html.contains("<p>Not drawn: "), "renders: {renders}");
    // The fits, the pictures (PNG and SVG), the R_A picture, the .bsdf and the renders.
    assert_eq!(links, 2 * models.len() + 2 * pictures + 1 + 1 + renders, "links in the report");
    // Numbers as a physicist writes them: no machine exponents in the text.
    let body = &html[html.find("<body>").unwrap()..];
    let machine = body
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-'))
        .find(|w| {
            w.contains('e')
                && w.split('e')
                    .all(|p| !p.is_empty() && p.trim_start_matches('-').replace('.', "").chars().all(|c| c.is_ascii_digit()))
        });
    assert_eq!(machine, None, "a number printed as the machine holds it");
    html
}

/// A simulated scan of `material` with its reference plate into
/// `dir/name`, calibrated: the path of its `calibrated.csv`. `grid` adds
/// the scan's grid options.
#[allow(dead_code)] // not every test binary that shares this module scans
pub fn calibrated_scan(dir: &std::path::Path, name: &str, material: &str, grid: &[&str]) -> std::path::PathBuf {
    let out = dir.join(name);
    let o = out.to_str().unwrap();
    let mut args = vec!["scan", "--sim", "--material", material, "--reference-plate", "--out", o, "--json"];
    args.extend_from_slice(grid);
    let s = gonio(&args);
    assert!(s.status.success(), "{}", text(&s));
    let c = gonio(&["calibrate", o, "--json"]);
    assert!(c.status.success(), "{}", text(&c));
    out.join("calibrated.csv")
}
