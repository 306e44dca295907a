//! `gonio fit --model rational` on a calibrated scan of the simulated head's
//! glass-bead layer (none of the models), its fit file read back and held
//! to every segment, and the mistakes a user makes with it.

mod common;
use common::{calibrated_scan, gonio, text};
use gonio_analysis::fit::data::theta_in;
use gonio_analysis::formats;
use gonio_analysis::rational::basis::Basis;
use gonio_analysis::rational::file::function_of;
use serde_json::Value;

fn fails_saying(args: &[&str], words: &[&str]) {
    let o = gonio(args);
    assert!(!o.status.success(), "{args:?} must fail: {}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|_| panic!("{args:?}: not JSON: {}", text(&o)));
    let e = v["error"].as_str().unwrap();
    for w in words {
        assert!(e.contains(w), "{args:?}: `{e}` does not say `{w}`");
    }
}

#[test]
fn a_glass_bead_scan_is_held_within_its_segments_and_mistakes_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let csv = calibrated_scan(dir.path(), "beads", "glass-beads", &["--theta-o", "0:84:6", "--dphi", "0:180:30"]);
    let file = csv.to_str().unwrap();
    let out = dir.path().join("rational.json");
    // The paper's absolute segments, at one incidence.
    let at_30 = ["fit", file, "--model", "rational", "--segments", "abs:0.5", "--theta-i", "30"];
    let o = gonio(&[&at_30[..], &["--param", "back", "--out", out.to_str().unwrap(), "--json"]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["model"], "rational");
    // The --param plane or ALTA's view plane, whichever held first.
    assert!(v["parametrization"] == "back" || v["parametrization"] == "view-projected", "{v}");
    assert_eq!(v["segments"], serde_json::json!({"kind": "absolute", "width": 0.5}));
    assert_eq!(v["worst_violation"], 0.0);
    let terms = v["terms"].as_u64().unwrap() as usize;
    assert_eq!(v["coefficients"].as_u64().unwrap() as usize, 2 * terms);
    assert_eq!(v["degree"].as_u64().unwrap() as usize, Basis::degree_of(terms));
    assert_eq!(v["cosine"], true);
    assert!(v["linf"].as_f64().unwrap() < 1.0, "{v}");
    // The fewest terms: one fewer was tried and could not be held.
    let attempts = v["attempts"].as_array().unwrap();
    assert!(
        attempts
            .iter()
            .any(|a| a["coefficients"].as_u64() == Some(2 * terms as u64 - 2) && a["feasible"] == false),
        "{v}"
    );

    // The file alone gives the function back, and it holds every segment.
    let saved: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert!(saved["support"].is_object(), "the fit file says what it rests on");
    let r = function_of(&saved).unwrap();
    let data = formats::load(&csv, None).unwrap();
    let fitted = data.filter(|o| theta_in(o.theta_i, &[30.0]));
    assert_eq!(v["samples"].as_u64().unwrap() as usize, fitted.observations.len());
    for o in &fitted.observations {
        let f = r.eval(&o.directions());
        let (lo, hi) = if o.value < 0.5 {
            (0.0, (o.value + 0.5).max(1.0))
        } else {
            (o.value - 0.5, o.value + 0.5)
        };
        assert!(f > lo && f < hi, "{f} outside [{lo}, {hi}]");
    }

    // `gonio eval` and `gonio dhr` take the fit file.
    let o = gonio(&[
        "eval",
        "--fit",
        out.to_str().unwrap(),
        "--theta-i",
        "30",
        "--theta-o",
        "29",
        "--dphi",
        "0",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let e: Value = serde_json::from_slice(&o.stdout).unwrap();
    let here = r.eval(&gonio_brdf::Directions::from_degrees(30.0, 29.0, 0.0));
    assert_eq!(e["model"], "rational");
    assert!((e["fr"].as_f64().unwrap() - here).abs() <= 1e-12 * here, "{e} against {here}");
    let o = gonio(&["dhr", "--fit", out.to_str().unwrap(), "--theta-i", "30", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let rho = serde_json::from_slice::<Value>(&o.stdout).unwrap()["dhr"].as_f64().unwrap();
    assert!(rho > 0.0 && rho.is_finite(), "ρ = {rho}");

    // `gonio export` writes it as a BRDF Explorer shader, its coefficients
    // inside (the shader is checked against the function in brdf_export.rs).
    let brdf = dir.path().join("rational.brdf");
    let o = gonio(&["export", out.to_str().unwrap(), brdf.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(serde_json::from_slice::<Value>(&o.stdout).unwrap()["model"], "rational");
    let shader = std::fs::read_to_string(&brdf).unwrap();
    assert!(
        shader.contains("::begin parameters\n::end parameters") && shader.contains("numerator +="),
        "{shader}"
    );

    // `gonio coefficients` takes it: values the data hold are theirs; beyond
    // them a rational function carries nothing (refused when alone, even
    // asked to extrapolate; the models' when a model's fit of the same data
    // is given too and an extrapolation asked for).
    let coefficients = |fits: &[&str]| -> Value {
        let mut args = vec!["coefficients", "--set", "astm-e810", "--rl", "--json", "--extrapolate"];
        for f in fits {
            args.extend(["--fit", f]);
        }
        let o = gonio(&args);
        assert!(o.status.success(), "{}", text(&o));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let alone = coefficients(&[out.to_str().unwrap()]);
    let values: Vec<&Value> = alone["ra"].as_array().unwrap().iter().chain([&alone["rl"]]).collect();
    assert!(values.len() > 1);
    for c in &values {
        let held = c["provenance"] == "measured" || c["provenance"] == "interpolated";
        assert_eq!(c["value"].is_number(), held, "{c}");
    }
    let model = dir.path().join("model.json");
    let o = gonio(
        &[
            &at_30[..2],
            &[
                "--model",
                "retro-phong",
                "--theta-i",
                "30",
                "--out",
                model.to_str().unwrap(),
                "--json",
            ],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", text(&o));
    let both = coefficients(&[out.to_str().unwrap(), model.to_str().unwrap()]);
    for c in both["ra"].as_array().unwrap().iter().chain([&both["rl"]]) {
        assert!(c["value"].is_number(), "{c}");
        if c["provenance"] == "extrapolated" {
            assert_eq!(c["model"], "retro-phong", "{c}");
            assert!(c["models"].as_array().unwrap().iter().all(|m| m["model"] != "rational"), "{c}");
        }
    }

    // `gonio plot` draws it over the data.
    let pictures = dir.path().join("plots");
    let o = gonio(&[
        "plot",
        file,
        "--out",
        pictures.to_str().unwrap(),
        "--fit",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let written = serde_json::from_slice::<Value>(&o.stdout).unwrap()["written"]
        .as_array()
        .unwrap()
        .len();
    assert!(written > 0 && pictures.join("residuals-30.svg").is_file(), "{written} pictures");

    // The text says what held, and which degrees were tried; --brdf and
    // --plot take the fit as they take a model's.
    let (brdf, plots) = (dir.path().join("fit.brdf"), dir.path().join("fit-plots"));
    let o = gonio(&[&at_30[..], &["--brdf", brdf.to_str().unwrap(), "--plot", plots.to_str().unwrap()]].concat());
    let t = text(&o);
    assert!(
        o.status.success() && t.contains("every segment held") && t.contains("coefficients tried"),
        "{t}"
    );
    assert!(brdf.is_file() && plots.join("residuals-30.svg").is_file());

    // Mistakes.
    fails_saying(
        &["fit", file, "--model", "rational", "--segments", "abs:0", "--json"],
        &["positive"],
    );
    fails_saying(
        &["fit", file, "--model", "rational", "--segments", "pct:3", "--json"],
        &["sigma", "abs:WIDTH"],
    );
    fails_saying(&["fit", file, "--model", "rational", "--bounds", "kd=0:1", "--json"], &["--bounds"]);
    fails_saying(
        &["fit", file, "--model", "rational", "--max-degree", "40", "--json"],
        &["at most 14"],
    );
    fails_saying(
        &["fit", file, "--model", "lambert", "--segments", "abs:1", "--json"],
        &["--model rational"],
    );
    // Segments no degree up to 2 holds: the error names the degree and a sample.
    fails_saying(
        &[
            "fit",
            file,
            "--model",
            "rational",
            "--segments",
            "rel:0.01",
            "--max-degree",
            "2",
            "--json",
        ],
        &["degree 2", "sample", "segment"],
    );
    // An ALTA file without intervals has no σ for `--segments sigma`.
    let alta = dir.path().join("plain.dat");
    let mut plain = data.clone();
    plain.observations.iter_mut().for_each(|o| o.sigma = None);
    std::fs::write(&alta, formats::alta::write(&plain)).unwrap();
    fails_saying(
        &["fit", alta.to_str().unwrap(), "--model", "rational", "--json"],
        &["no uncertainty", "abs:WIDTH"],
    );
}
