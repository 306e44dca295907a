//! `gonio moments` on scans of the simulated head: a tape whose retro lobe
//! is a power of `l·v` is isotropic about the light (Belcour's light-view
//! plane) and anisotropic in the back plane at grazing light; a threshold
//! that lets the lobe reach the head's blind zone is said to be
//! under-sampled; bad input is refused with a non-zero exit.

mod common;
use common::{calibrated_scan, gonio, text};
use serde_json::Value;

fn moments(file: &str, extra: &[&str]) -> Value {
    let mut args = vec!["moments", file, "--json"];
    args.extend_from_slice(extra);
    let o = gonio(&args);
    assert!(o.status.success(), "{}", text(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `(θi, plane, moments)` of every incidence.
fn rows(v: &Value) -> Vec<(f64, String, Value)> {
    v["incidences"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["theta_i_deg"].as_f64().unwrap(),
                e["parametrization"].as_str().unwrap().to_string(),
                e["moments"].clone(),
            )
        })
        .collect()
}

#[test]
fn a_tape_is_isotropic_about_the_light_and_its_moments_say_what_they_rest_on() {
    let dir = tempfile::tempdir().unwrap();
    // The paper's incidences; a coarse grid away from the lobes, the
    // head's retro rings (to 4.75°) about the light.
    let file = calibrated_scan(dir.path(), "tape", "retro-phong", &["--theta-o", "0:84:6", "--dphi", "0:180:30"]);
    let file = file.to_str().unwrap();

    let plots = dir.path().join("plots");
    let v = moments(file, &["--plot", plots.to_str().unwrap()]);
    assert_eq!(v["order"], 4);
    let all = rows(&v);
    assert_eq!(all.len(), 6, "three incidences in two planes: {v}");
    for (ti, plane, m) in &all {
        let r = m["r"].as_f64().unwrap();
        assert_eq!(m["under_sampled"], false, "θi {ti} {plane}: {m}");
        assert_eq!(m["truncated"], false, "θi {ti} {plane}: {m}");
        assert_eq!(m["central"].as_array().unwrap().len(), 12, "orders 2 to 4");
        match plane.as_str() {
            "light-view" => assert!(r < 0.05, "θi {ti}: r = {r} about the light"),
            // The back vector halves the angle in the plane of incidence
            // and divides it by 2cosθi across: σy/σx → 1/cosθi.
            _ if *ti == 60.0 => assert!(r > 0.5, "θi 60° back plane: r = {r}"),
            _ => {}
        }
    }
    for name in ["moments.png", "moments.svg"] {
        assert!(std::fs::metadata(plots.join(name)).unwrap().len() > 1000, "{name}");
    }

    // At 10 % the tape's lobe (σ ≈ 2.6° about the light) reaches the blind
    // zone, and the moments say so.
    let low = moments(file, &["--threshold", "rel:0.1"]);
    for (ti, plane, m) in rows(&low) {
        assert_eq!(m["under_sampled"], true, "θi {ti} {plane}: {m}");
        assert!(m["gap_sigma"].as_f64().unwrap() > 2.0, "θi {ti} {plane}: {m}");
    }
    let t = gonio(&["moments", file, "--threshold", "rel:0.1"]);
    assert!(t.status.success() && text(&t).contains("gap/σ > 1"), "{}", text(&t));

    // Bad input: a threshold out of range, a threshold above every value.
    let bad = gonio(&["moments", file, "--threshold", "rel:1.5"]);
    assert_eq!(bad.status.code(), Some(2), "{}", text(&bad));
    assert!(text(&bad).contains("between 0 and 1"), "{}", text(&bad));
    let none = gonio(&["moments", file, "--threshold", "1e9", "--json"]);
    assert!(!none.status.success());
    let e: Value = serde_json::from_slice(&none.stdout).unwrap();
    assert!(e["error"].as_str().unwrap().contains("no retro lobe"), "{e}");
}
