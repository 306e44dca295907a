//! The `gonio` binary as a user runs it: help everywhere, the demo's files,
//! and clean failures.

use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;

mod common;
use common::{gonio, text};

#[test]
fn every_command_has_help() {
    for cmd in [
        &["--help"][..],
        &["demo", "--help"],
        &["scan", "--help"],
        &["devices", "--help"],
        &["sim", "--help"],
        &["fit", "--help"],
        &["convert", "--help"],
        &["compare", "--help"],
        &["calibrate", "--help"],
        &["plot", "--help"],
        &["export", "--help"],
        &["eval", "--help"],
        &["dhr", "--help"],
    ] {
        let o = gonio(cmd);
        assert!(o.status.success(), "{cmd:?}: {}", text(&o));
        assert!(text(&o).contains("Usage"), "{cmd:?}");
    }
    // What a command writes is in its first line, for `gonio --help`.
    for help in [gonio(&["export", "--help"]), gonio(&["--help"])] {
        let said = text(&help);
        for format in [".brdf", ".bsdf", ".binary"] {
            assert!(said.contains(format), "{said}");
        }
    }
}

#[test]
fn devices_lists_heads_as_json() {
    let o = gonio(&["devices", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let list: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // No head is plugged into the test machine.
    assert_eq!(list, serde_json::json!([]));
}

#[test]
fn an_unreachable_port_fails_cleanly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    let o = gonio(&["scan", "--port", "/nonexistent", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let msg = text(&o);
    assert!(msg.contains("error: cannot open the head's port /nonexistent"), "{msg}");
    assert!(!msg.contains("panicked"), "{msg}");
    assert!(!out.exists(), "output directory created for a failed scan");
}

#[test]
fn user_mistakes_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let out = out.to_str().unwrap();
    for (args, says) in [
        (vec!["scan", "--sim", "--out", out, "--theta-o", "0:90"], "START:STOP:STEP"),
        (
            vec!["scan", "--sim", "--out", out, "--material", "glitter"],
            "valid models: lambert, retro-phong",
        ),
        (
            vec!["scan", "--sim", "--out", out, "--material", "lambert", "--params", "rho=1"],
            "valid: kd",
        ),
        (vec!["scan", "--out", out], "required"),
        (
            vec!["scan", "--port", "/dev/null", "--out", out, "--inject", "drop@3"],
            "--inject acts on the simulated head only",
        ),
        (vec!["scan", "--sim", "--out", out, "--theta-i", "100"], "100° is not an incidence"),
        (vec!["scan", "--sim", "--out", out, "--theta-i", "-10"], "-10° is not an incidence"),
        (vec!["scan", "--sim", "--out", out, "--theta-o", "0:95:5"], "beyond the view angles"),
        (vec!["scan", "--resume", out, "--theta-i", "10"], "cannot be used with '--theta-i"),
        (vec!["scan", "--resume", out, "--integration-s", "1"], "cannot be used with"),
        (vec!["scan", "--resume", out, "--material", "lambert"], "cannot be used with"),
        (vec!["calibrate", "/nonexistent"], "/nonexistent is not a scan directory"),
        (
            vec!["scan", "--sim", "--out", out, "--integration-s", "-1"],
            "--integration-s -1 s: a point's integration time must be longer than 0 s",
        ),
        (
            vec!["scan", "--sim", "--out", out, "--theta-o", "0:80:0.0001"],
            "positions: more than the 10000000 a scan holds",
        ),
        (
            vec!["fit", "/dev/null", "--model", "glitter"],
            "five-param, or `rational` (the rational function)",
        ),
    ] {
        let o = gonio(&args);
        assert!(!o.status.success(), "{args:?}");
        let msg = text(&o);
        assert!(msg.contains(says), "{args:?}: {msg}");
        assert!(!msg.contains("panicked"), "{msg}");
    }
}

/// A sweep scan slows down for the narrowest lobe of a fitted model, and says
/// so in run.json; a model without lobes, a missing file or a width out of
/// range are errors.
#[test]
fn a_sweep_scan_takes_its_lobe_width_from_a_fit_file() {
    let dir = tempfile::tempdir().unwrap();
    let fit = |name: &str, model: &str, params: &str| {
        let path = dir.path().join(name);
        let text = format!("{{\"model\": \"{model}\", \"parametrization\": \"view\", \"params\": {{{params}}}}}");
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    let tape = fit(
        "tape.json",
        "retro-phong",
        "\"kd\": 0.05, \"n\": 1000, \"k1\": 0.4, \"k2\": 0.05, \"k3\": 0.02, \"k4\": 3",
    );
    let flat = fit("flat.json", "lambert", "\"kd\": 0.5");
    let out = dir.path().join("scan");
    let out = out.to_str().unwrap();
    let row = ["--theta-i", "30", "--theta-o", "0:60:3", "--dphi", "180:180:10", "--sweep"];
    let scan = |extra: &[&str]| gonio(&[&["scan", "--sim", "--out", out, "--force", "--json"], &row[..], extra].concat());
    let o = scan(&["--sweep-lobe-from", &tape]);
    assert!(o.status.success(), "{}", text(&o));
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(Path::new(out).join("run.json")).unwrap()).unwrap();
    let lobe = &run["grid"]["sweep"]["lobe"];
    let want = (-0.5f64 / 1000.0).exp().acos().to_degrees();
    let width = lobe["width_deg"].as_f64().unwrap();
    assert!((width - want).abs() < 0.02 * want, "{width}° against {want}°");
    assert_eq!(lobe["extent_fraction"].as_f64(), Some(0.25));
    for (extra, says) in [
        (vec!["--sweep-lobe-from", flat.as_str()], "no retro or mirror lobe"),
        (vec!["--sweep-lobe-from", "/nonexistent/fit.json"], "cannot read"),
        (vec!["--sweep-lobe", "0.01"], "the width must lie in"),
        (vec!["--sweep-lobe", "2", "--sweep-extent", "1.5"], "the extent in (0, 1]"),
    ] {
        let o = scan(&extra);
        assert!(!o.status.success(), "{extra:?}");
        let msg = text(&o);
        assert!(msg.contains(says) && !msg.contains("panicked"), "{extra:?}: {msg}");
    }
    let o = gonio(&["scan", "--sim", "--out", out, "--sweep-lobe", "2"]);
    assert!(!o.status.success() && text(&o).contains("--sweep"), "{}", text(&o));
}

/// A sweep scan recorded under an earlier protocol (its rows and retro
/// points elsewhere), or by a gonio that did not keep it, is not resumed
/// into a mix of the two layouts; a grid scan, unchanged, is.
#[test]
fn a_sweep_scan_recorded_under_another_protocol_is_not_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("sweep", Some(11), "protocol 11"),
        ("sweep", None, "an earlier gonio"),
        ("grid", Some(11), ""),
        ("grid", None, ""),
    ];
    for (k, (name, protocol, says)) in cases.into_iter().enumerate() {
        let out = dir.path().join(format!("{name}{k}"));
        let extra = if name == "sweep" { &["--sweep"][..] } else { &[][..] };
        let args = [
            &[
                "scan",
                "--sim",
                "--out",
                out.to_str().unwrap(),
                "--theta-i",
                "30",
                "--theta-o",
                "0:60:6",
                "--dphi",
                "180:180:10",
            ][..],
            extra,
        ]
        .concat();
        let o = gonio(&args);
        assert!(o.status.success(), "{}", text(&o));
        // Interrupted as if killed, under protocol 11 or by a gonio that
        // did not keep its protocol.
        std::fs::rename(out.join("samples.csv"), out.join("samples.csv.part")).unwrap();
        let plan = out.join("scan.json");
        let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan).unwrap()).unwrap();
        assert_eq!(json["protocol"].as_u64(), Some(gonio_shared::PROTOCOL_VERSION as u64));
        match protocol {
            Some(p) => json["protocol"] = p.into(),
            None => _ = json.as_object_mut().unwrap().remove("protocol"),
        }
        std::fs::write(&plan, json.to_string()).unwrap();
        let o = gonio(&["scan", "--resume", out.to_str().unwrap()]);
        match name {
            "sweep" => assert!(!o.status.success() && text(&o).contains(says), "{}", text(&o)),
            _ => assert!(o.status.success(), "{}", text(&o)),
        }
    }
}

fn csv_indices(path: &Path) -> Vec<u32> {
    csv_column(path, "index")
}

/// A column of numbers of a samples file.
fn csv_column(path: &Path, name: &str) -> Vec<u32> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == name).unwrap();
    lines.map(|l| l.split(',').nth(col).unwrap().parse().unwrap()).collect()
}

/// The demo's whole chain: scan (once per reachable point), calibration,
/// comparison, report.
#[test]
fn demo_scans_the_belcour_grid_once_per_reachable_point() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = gonio(&["demo", "--out", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (points, measured, skipped) = (
        summary["points"].as_u64().unwrap(),
        summary["measured"].as_u64().unwrap(),
        summary["skipped"].as_u64().unwrap(),
    );
    // The grid and, at each incidence, its lobe patterns (docs/optics.md),
    // at the Belcour incidences and those ASTM E810 and EN 1436 add (4°,
    // 40°, 45°, 88.76°), with EN 1436's 1.05° ring among the CEA rings.
    assert_eq!(points, 7 * (31 * 37 + 11 * 32 + 5 * 16));
    assert_eq!(measured + skipped, points);
    // θo = 90° is behind the sample for every (θi, Δφ): 3 × 37 points at least.
    assert!(skipped >= 111, "{summary}");
    // R_A and R_L as the report gives them, each saying what it rests on.
    // The scan measured every one of them: none rests on a model.
    let ra = summary["coefficients"]["ra"].as_array().expect("R_A in the demo's JSON");
    assert!(!ra.is_empty() && ra.iter().all(|c| c["provenance"] == "measured"), "{summary}");
    let rl = &summary["coefficients"]["rl"];
    assert_eq!(rl["provenance"], "measured", "{rl}");
    let truth = serde_json::from_slice::<serde_json::Value>(
        &gonio(&["coefficients", "--material", "glass-beads", "--set", "en1436", "--json"]).stdout,
    )
    .unwrap()["rl"]["value"]
        .as_f64()
        .unwrap();
    let (v, u) = (rl["value"].as_f64().unwrap(), rl["u"].as_f64().unwrap());
    assert!((v - truth).abs() <= 2.0 * u, "R_L {v} ± {u} against the material's {truth}");
    let idx = csv_indices(&out.join("samples.csv"));
    assert_eq!(idx.len() as u64, measured);
    assert_eq!(idx.iter().collect::<BTreeSet<_>>().len(), idx.len(), "duplicate points");
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["complete"], true);
    assert_eq!(run["counts"]["measured"].as_u64(), Some(measured));
    assert_eq!(run["grid"]["points"].as_u64(), Some(points));
    assert_eq!(run["head"]["simulated"], true);
    assert!(!out.join("samples.csv.part").exists());
    // Calibrated on the virtual plate, every model fitted. The material is
    // a physical glass-bead layer, none of the models: the summary names it,
    // and no model describes it exactly.
    // Every sample is usable but views within a degree of the horizon at
    // 88.76°, whose light is at the detector's noise (below it, or its
    // phase lost in it).
    let mut r = csv::Reader::from_path(out.join("calibrated.csv")).unwrap();
    let h = r.headers().unwrap().clone();
    let col = |n: &str| h.iter().position(|x| x == n).unwrap();
    let (usable, to, flags) = (col("usable"), col("theta_o_deg"), col("flag_names"));
    let unusable: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).filter(|x| &x[usable] == "false").collect();
    assert!(
        unusable
            .iter()
            .all(|x| x[to].parse::<f64>().unwrap() > 89.0 && (x[flags].contains("below_noise") || x[flags].contains("phase_off"))),
        "{unusable:?}"
    );
    assert_eq!(summary["calibration"]["usable"].as_u64(), Some(measured - unusable.len() as u64));
    // The rational function through the samples' k = 2 intervals is
    // fitted beside them, or the summary says why not.
    let rational = summary["models"].as_array().unwrap().iter().any(|m| m["model"] == "rational");
    let unfitted = summary["unfitted"].as_array().unwrap();
    assert_eq!(unfitted.len(), usize::from(!rational), "{}", summary["unfitted"]);
    assert_eq!(
        summary["models"].as_array().unwrap().len(),
        gonio_brdf::ModelId::ALL.len() + usize::from(rational)
    );
    assert!(summary["material"].as_str().unwrap().contains("glass-bead"), "{summary}");
    let ncc: Vec<f64> = summary["models"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["model"] != "rational")
        .map(|m| m["ncc"].as_f64().unwrap())
        .collect();
    assert!(ncc.iter().all(|&c| c < 0.99), "no model is the material: NCC {ncc:?}");
    let models: Vec<&str> = summary["models"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["model"].as_str().unwrap())
        .collect();
    common::check_report(&out, &models, &["4", "15", "30", "40", "45", "60", "88.76"]);
    // The README's commands on the demo's own output: every fit file reads
    // back (abc-retro's and its per-lobe twin's covariances included).
    let fits: Vec<String> = std::fs::read_dir(out.join("fits"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .map(|p| p.to_str().unwrap().to_string())
        .collect();
    assert!(fits.len() >= gonio_brdf::ModelId::ALL.len(), "{fits:?}");
    for extra in [&[][..], &["--extrapolate"]] {
        let mut args = vec!["coefficients", "--set", "astm-e810", "--set", "en1436", "--json", "--fit"];
        args.extend(fits.iter().map(String::as_str));
        args.extend_from_slice(extra);
        let o = gonio(&args);
        assert!(o.status.success(), "{args:?}: {}", text(&o));
    }
    for f in fits.iter().filter(|f| !f.ends_with("rational.json")) {
        let o = gonio(&["export", f, out.join("x.brdf").to_str().unwrap()]);
        assert!(o.status.success(), "export {f}: {}", text(&o));
    }
    // A second demo into the same directory is refused rather than mixed in.
    let again = gonio(&["demo", "--out", out.to_str().unwrap()]);
    assert!(!again.status.success());
    assert!(text(&again).contains("already holds a scan"));
}

/// Runs `gonio scan --sim --out OUT` with `extra` options and kills it with
/// SIGKILL once more than `lines` samples are on disk.
fn scan_killed(out: &Path, extra: &[&str], lines: usize) {
    use std::time::{Duration, Instant};
    let mut child = Command::new(env!("CARGO_BIN_EXE_gonio"))
        .args([&["scan", "--sim", "--out", out.to_str().unwrap()], extra].concat())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let part = out.join("samples.csv.part");
    let t0 = Instant::now();
    loop {
        let rows = std::fs::read_to_string(&part).map(|t| t.lines().count()).unwrap_or(0);
        if rows > lines || t0.elapsed() > Duration::from_secs(120) {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("samples.csv").exists(), "the scan finished before it was killed");
}

#[test]
fn a_scan_killed_at_a_random_point_resumes_to_exactly_the_grid() {
    use rand::Rng;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    // Killed once a random number of samples are on disk.
    let kill_after = rand::rng().random_range(20..1500);
    scan_killed(&out, &[], kill_after);
    let part = out.join("samples.csv.part");

    let o = gonio(&["scan", "--resume", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let idx = csv_indices(&out.join("samples.csv"));
    let unique: BTreeSet<u32> = idx.iter().copied().collect();
    assert_eq!(
        unique.len(),
        idx.len(),
        "a point was measured twice (killed after {kill_after} rows)"
    );
    let reachable = common::reachable(&gonio_shared::ScanSpec::belcour_with_patterns());
    assert_eq!(unique, reachable, "points missing after resuming (killed after {kill_after} rows)");
    assert!(!part.exists());
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["counts"]["measured"].as_u64(), Some(idx.len() as u64));
    // A complete scan is not resumed again.
    let again = gonio(&["scan", "--resume", out.to_str().unwrap()]);
    assert!(!again.status.success());
    assert!(text(&again).contains("complete scan"));
}

#[test]
fn a_sweep_scan_killed_at_a_random_point_resumes_to_every_position_once_and_whole() {
    use rand::Rng;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sweep");
    // Some 90 samples a row, 111 rows, 3 retro points and 1 200 pattern
    // points (an incidence's retro point and pattern before its rows):
    // killed within one of them or between.
    let kill_after = rand::rng().random_range(50..9000);
    scan_killed(&out, &["--sweep"], kill_after);
    let o = gonio(&["scan", "--resume", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    // Each position's samples stand together, once, and whole: consecutive
    // sample numbers of one sweep (the last row stored before the kill was
    // dropped and swept again; kept beside its first sweep, its samples
    // would continue the row with the new run's numbers).
    let path = out.join("samples.csv");
    let (idx, seq) = (csv_indices(&path), csv_column(&path, "seq"));
    let mut runs: Vec<(u32, usize)> = Vec::new();
    for (k, i) in idx.iter().enumerate() {
        match runs.last_mut() {
            Some((r, n)) if r == i => {
                assert_eq!(
                    seq[k],
                    seq[k - 1] + 1,
                    "row {i} is not one sweep (killed after {kill_after} samples)"
                );
                *n += 1;
            }
            _ => runs.push((*i, 1)),
        }
    }
    let positions: BTreeSet<u32> = runs.iter().map(|r| r.0).collect();
    assert_eq!(
        positions.len(),
        runs.len(),
        "a position stored twice (killed after {kill_after} samples)"
    );
    assert_eq!(
        positions,
        (0..114 + 3 * 400).collect(),
        "positions missing after resuming (killed after {kill_after} samples)"
    );
    // Each incidence's retro point and its 400 pattern points one sample
    // (positions 0 and 38.. of its 438), its rows many.
    let at_rest = |i: u32| i % 438 == 0 || i % 438 >= 38;
    assert!(
        runs.iter().all(|&(i, n)| if at_rest(i) { n == 1 } else { n > 20 }),
        "a row cut short or a point measured twice: {runs:?}"
    );
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["counts"]["measured"].as_u64(), Some(114 + 3 * 400));
    assert_eq!(run["counts"]["swept_samples"].as_u64(), Some(idx.len() as u64 - 3 - 3 * 400));
}

/// A drift monitor or a learning geometry the head cannot reach is refused
/// once the head has said what it reaches, before anything moves, and no
/// scan directory is left behind.
#[test]
fn an_unreachable_monitor_is_refused_before_the_first_move() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    let grid = ["--theta-i", "30", "--theta-o", "0:30:10", "--dphi", "0:0:1", "--no-patterns"];
    for (option, at, says) in [
        ("--monitor", "30,95,0", "behind the sample plane"),
        ("--learn-at", "30,24,0", "blind zone"),
    ] {
        let o = gonio(&[&["scan", "--sim", "--out", out.to_str().unwrap(), option, at][..], &grid].concat());
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        let msg = text(&o);
        assert!(msg.contains(&format!("{option} {at}")) && msg.contains(says), "{msg}");
        assert!(!out.exists(), "{option}: a directory for a scan that cannot run");
    }
}

/// Data files with directions no measurement has are refused, row named:
/// an incidence or a view beyond 90° or below 0°, a Δφ beyond a turn, an
/// ALTA direction below the sample plane.
#[test]
fn impossible_angles_in_data_files_are_refused_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let csv = |name: &str, row: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, format!("theta_i_deg,theta_o_deg,dphi_deg,brdf_sr\n30,30,0,1\n{row}\n")).unwrap();
        p.to_str().unwrap().to_string()
    };
    let alta = dir.path().join("below.dat");
    // Spherical angles in radians: the second sample's view at θ = 2.0 rad.
    std::fs::write(
        &alta,
        "#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n#VS 0\n0.5 0 0.5 3.14159 1\n0.5 0 2.0 3.14159 1\n",
    )
    .unwrap();
    let files = [
        (csv("ti.csv", "100,30,0,1"), "line 3: θi = 100° is not an incidence angle"),
        (csv("neg.csv", "-10,30,0,1"), "line 3: θi = -10° is not an incidence angle"),
        (csv("to.csv", "30,95,0,1"), "line 3: θo = 95° is not a view angle"),
        (csv("dphi.csv", "30,30,400,1"), "line 3: Δφ = 400° is outside"),
        (alta.to_str().unwrap().to_string(), "line 6: θo = 114.5916° is not a view angle"),
    ];
    for (file, says) in &files {
        for cmd in [
            vec!["fit", file, "--model", "lambert"],
            vec!["convert", file, "/dev/null"],
            vec!["coefficients", "--data", file],
        ] {
            let o = gonio(&cmd);
            let msg = text(&o);
            assert_eq!(o.status.code(), Some(1), "{cmd:?}: {msg}");
            assert!(msg.contains(says), "{cmd:?}: {msg}");
        }
    }
}

/// Under `--json` every subcommand prints one JSON object on stdout, on
/// success and on failure (`{"error", "kind"}`), with the same exit codes.
#[test]
fn every_subcommand_speaks_json_on_failure_and_success() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let good = at("good.csv");
    std::fs::write(
        &good,
        "theta_i_deg,theta_o_deg,dphi_deg,brdf_sr\n30,30,0,0.2\n30,40,0,0.2\n30,50,180,0.2\n",
    )
    .unwrap();
    let fit = at("fit.json");
    std::fs::write(&fit, r#"{"model": "lambert", "parametrization": "view", "params": {"kd": 0.5}}"#).unwrap();
    let (missing, out) = (at("missing.csv"), at("out"));
    let failing: Vec<(Vec<&str>, &str, i32)> = vec![
        (vec!["scan", "--sim", "--out", &out, "--theta-i", "100"], "input", 1),
        (vec!["demo", "--out", "/dev/null/x"], "io", 1),
        (vec!["calibrate", "/nonexistent"], "input", 1),
        (vec!["coefficients", "--data", &missing], "io", 1),
        (vec!["fit", &missing, "--model", "lambert"], "io", 1),
        (vec!["compare", &missing], "io", 1),
        (vec!["plot", &missing, "--out", &out], "io", 1),
        (vec!["convert", &missing, &out], "io", 1),
        (vec!["export", &missing, &out], "io", 1),
        (
            vec![
                "eval",
                "--model",
                "lambert",
                "--params",
                "kd=0.5",
                "--theta-i",
                "100",
                "--theta-o",
                "0",
                "--dphi",
                "0",
            ],
            "input",
            1,
        ),
        (
            vec!["dhr", "--model", "lambert", "--params", "kd=0.5", "--theta-i", "100"],
            "input",
            1,
        ),
        (vec!["fit", "--model", "lambert"], "usage", 2),
        (vec!["pause", &out], "io", 1),
        (vec!["continue", &out], "io", 1),
        (vec!["abort", &out], "io", 1),
        (vec!["rearm", "--port", "/nonexistent/tty"], "input", 1),
    ];
    for (args, kind, code) in failing {
        let o = gonio(&[&args[..], &["--json"]].concat());
        assert_eq!(o.status.code(), Some(code), "{args:?}: {}", text(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}: {}", text(&o)));
        assert_eq!(v["kind"], kind, "{args:?}: {v}");
        assert!(v["error"].as_str().is_some_and(|e| !e.is_empty()), "{args:?}: {v}");
    }
    let (brdf, dat, plots) = (at("fit.brdf"), at("good.dat"), at("plots"));
    let succeeding: Vec<(Vec<&str>, &str)> = vec![
        (vec!["convert", &good, &dat], "samples"),
        (vec!["export", &fit, &brdf], "model"),
        (vec!["plot", &good, "--out", &plots, "--fit", &fit], "written"),
        (vec!["devices"], ""),
    ];
    for (args, key) in succeeding {
        let o = gonio(&[&args[..], &["--json"]].concat());
        assert!(o.status.success(), "{args:?}: {}", text(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}: {}", text(&o)));
        assert!(key.is_empty() || !v[key].is_null(), "{args:?}: {v}");
    }
}

/// A scan paused from another terminal holds (no sample stored while it
/// waits, the head kept awake), continues where it stopped when asked, and
/// ends with every point; the live view's record is gone with the scan.
#[test]
fn a_scan_pauses_and_continues_from_another_terminal() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    let o = out.to_str().unwrap();
    let scan = std::process::Command::new(env!("CARGO_BIN_EXE_gonio"))
        .args([
            "scan",
            "--sim",
            "--out",
            o,
            "--theta-i",
            "30",
            "--theta-o",
            "0:87:3",
            "--dphi",
            "-180:170:10",
            "--json",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let live = out.join("live.json");
    let waited = std::time::Instant::now();
    while !live.exists() {
        assert!(waited.elapsed().as_secs() < 60, "no live.json");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let p = gonio(&["pause", o, "--json"]);
    assert!(p.status.success(), "{}", text(&p));
    let v: serde_json::Value = serde_json::from_slice(&p.stdout).unwrap();
    assert_eq!(v["request"], "pause", "{v}");
    let served: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&live).unwrap()).unwrap();
    let state = || -> serde_json::Value {
        let text = ureq::get(format!("{}/api/state", served["origin"].as_str().unwrap()))
            .header("X-Gonio-Token", served["token"].as_str().unwrap())
            .call()
            .unwrap()
            .body_mut()
            .read_to_string()
            .unwrap();
        serde_json::from_str(&text).unwrap()
    };
    while state()["state"]["state"] != "paused" {
        assert!(waited.elapsed().as_secs() < 120, "never paused: {}", state()["state"]);
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let held = state()["samples"].as_array().unwrap().len();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    assert_eq!(state()["samples"].as_array().unwrap().len(), held, "samples while paused");
    let c = gonio(&["continue", o]);
    assert!(c.status.success(), "{}", text(&c));
    let done = scan.wait_with_output().unwrap();
    assert!(done.status.success(), "{}", text(&done));
    let outcome: serde_json::Value = serde_json::from_slice(&done.stdout).unwrap();
    // The grid's 1 080 points and the lobe pattern's rings about the light.
    let points = outcome["points"].as_u64().unwrap();
    assert!(
        points > 1080 && (held as u64) < points,
        "paused before the end ({held} of {points})"
    );
    assert_eq!(
        outcome["measured"].as_u64().unwrap() + outcome["skipped"].as_u64().unwrap(),
        points,
        "{outcome}"
    );
    assert!(
        outcome["recoveries"].as_object().unwrap().is_empty(),
        "a pause is not a recovery: {outcome}"
    );
    assert!(!live.exists(), "live.json outlives its scan");
}

#[test]
fn export_writes_an_rgl_bsdf_and_says_how_closely_it_holds_the_material() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tape.bsdf");
    let path = out.to_str().unwrap();
    let tape = ["--material", "retro-phong", "--params", "kd=0.05,n=1000,k1=0.8,k2=0.1,k3=0.02,k4=3"];
    let o = gonio(&[&["export"], &tape[..], &[path, "--json"]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["format"], "rgl-bsdf");
    assert_eq!(v["within_tolerance"], true, "{v}");
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(&bytes[..12], b"tensor_file\0");
    assert_eq!(v["bytes"], bytes.len());
    // Too coarse for the beads' ring at the defaults: written, with a warning naming the error.
    let o = gonio(&["export", "--material", "glass-beads", path]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("warning: the table is too coarse"), "{}", text(&o));
    // MERL: the three dimensions, then three channels of doubles.
    let merl = dir.path().join("beads.binary");
    let o = gonio(&["export", "--material", "glass-beads", merl.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let bytes = std::fs::read(&merl).unwrap();
    assert_eq!(bytes.len(), 12 + 3 * 90 * 90 * 180 * 8);
    assert_eq!(&bytes[..12], [90i32, 90, 180].map(i32::to_le_bytes).concat());
    // Mistakes: a material with a fit, a format we do not write, a shader from a material.
    for (args, needle) in [
        (vec!["export", "--material", "glass-beads", "fit.json", path], "only OUTPUT"),
        (vec!["export", "--material", "glass-beads", "x.txt"], "extension"),
        (vec!["export", "--material", "glass-beads", "x.brdf"], "from a fit"),
    ] {
        let o = gonio(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(text(&o).contains(needle), "{args:?}: {}", text(&o));
    }
}

/// A grazing incidence whose beam footprint would overfill the declared
/// sample is refused before anything moves, with the incidence the sample
/// does hold, and leaves no files.
#[test]
fn a_footprint_that_overfills_the_sample_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    let o = gonio(&[
        "scan",
        "--sim",
        "--theta-i",
        "30,88.76",
        "--theta-o",
        "0:60:30",
        "--dphi",
        "0:0:1",
        "--no-patterns",
        "--sample-size-mm",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(
        t.contains("θi 88.76°") && t.contains("overfills the 50 mm sample") && t.contains("up to 88.1°"),
        "{t}"
    );
    assert!(!out.join("scan.json").exists());
}
