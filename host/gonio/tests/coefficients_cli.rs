//! `gonio coefficients` (R_A, R_L) from a model, a fit and
//! measured data, and the uncertainty budget carried from the calibrated
//! samples through the fit to the coefficients, on an imperfect simulated head.

use gonio_analysis::coefficients::{self, Set, Source};
use gonio_analysis::fit;
use gonio_analysis::fit::file::FittedBrdf;
use gonio_analysis::formats;
use gonio_brdf::Material;
use serde_json::Value;
mod common;
use common::{gonio, text};

fn json(args: &[&str]) -> Value {
    let o = gonio(args);
    assert!(o.status.success(), "gonio {args:?}: {}", text(&o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&o)))
}

fn ra_at(v: &Value, alpha: f64, beta: f64, epsilon: f64) -> &Value {
    v["ra"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| {
            (e["alpha_deg"].as_f64().unwrap() - alpha).abs() < 1e-9
                && (e["beta_deg"].as_f64().unwrap() - beta).abs() < 1e-9
                && (e["epsilon_deg"].as_f64().unwrap() - epsilon).abs() < 1e-9
        })
        .unwrap_or_else(|| panic!("no R_A at α {alpha}, β {beta}, ε {epsilon}"))
}

/// `gonio coefficients --json` of a Lambertian `kd = 0.5` with these geometry options.
fn lambert(geometry: &[&str]) -> Value {
    let mut args = vec!["coefficients", "--model", "lambert", "--params", "kd=0.5", "--json"];
    args.extend_from_slice(geometry);
    json(&args)
}

#[test]
fn lambertian_ra_and_rl_by_the_named_sets() {
    let v = lambert(&["--set", "astm-e810", "--set", "en1436"]);
    assert_eq!(v["ra"].as_array().unwrap().len(), 70);
    for eps in [0.0, 90.0] {
        let ra = ra_at(&v, 0.2, -4.0, eps);
        let value = ra["value"].as_f64().unwrap();
        assert!((value - 0.15838).abs() < 1e-3, "R_A {value}");
        assert_eq!(ra["u"].as_f64(), Some(0.0), "a model without covariance has no uncertainty");
    }
    let rl = &v["rl"];
    assert!((rl["value"].as_f64().unwrap() - 3.444).abs() < 1e-3, "R_L {rl}");
    assert!((rl["alpha_deg"].as_f64().unwrap() - 1.05).abs() < 1e-12);
    assert!((rl["beta_deg"].as_f64().unwrap() - 88.76).abs() < 1e-9);
    // A model is no instrument's measurement: no wavelength to state.
    assert!(v["wavelength_nm"].is_null() && v["instrument"].is_null(), "{v}");
    // A negative entrance angle in a list, as the README writes it.
    let v = lambert(&["--alpha", "0.2", "--beta", "-4,30"]);
    assert_eq!(v["ra"].as_array().unwrap().len(), 2);
    assert!((ra_at(&v, 0.2, -4.0, 0.0)["value"].as_f64().unwrap() - 0.15838).abs() < 1e-3);
    // The text output says the values are not photometric.
    let o = gonio(&["coefficients", "--model", "lambert", "--params", "kd=0.5", "--rl"]);
    assert!(o.status.success() && text(&o).contains("not photometric"), "{}", text(&o));
}

#[test]
fn bad_requests_are_refused_with_a_reason() {
    for (args, says) in [
        (vec!["coefficients", "--model", "lambert", "--params", "kd=0.5"], "no geometry"),
        (vec!["coefficients", "--set", "en1436"], "give a BRDF"),
        (
            vec!["coefficients", "--model", "lambert", "--params", "kd=0.5", "--alpha", "0.2"],
            "go together",
        ),
        (
            vec![
                "coefficients",
                "--model",
                "lambert",
                "--params",
                "kd=0.5",
                "--alpha",
                "2",
                "--beta",
                "89.99",
            ],
            "behind the sample",
        ),
    ] {
        let o = gonio(&args);
        assert!(!o.status.success() && text(&o).contains(says), "{args:?}: {}", text(&o));
    }
}

/// The whole chain on an imperfect simulated head: every calibrated value
/// carries its budget (components in calibrated.csv, k = 2 intervals in the
/// ALTA export), a retro-phong fit weighted by it gives R_A and R_L within
/// their k = 2 intervals of the material's own, linear propagation agrees
/// with Monte Carlo, and the data path names the geometries it used.
#[test]
fn coefficients_of_a_fitted_scan_hold_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let scan = dir.path().join("scan");
    let s = scan.to_str().unwrap();
    let o = gonio(&[
        "scan",
        "--sim",
        "--material",
        "retro-phong",
        "--imperfect",
        "--seed",
        "1",
        "--reference-plate",
        "--out",
        s,
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let cal = json(&["calibrate", s, "--json"]);
    assert_eq!(cal["slope_model"]["model"], "retro-phong");
    assert_eq!(cal["budget"].as_array().unwrap().len(), 3, "one budget per θi");

    // calibrated.csv: the components and the interval, consistent with the combined value.
    let csv = scan.join("calibrated.csv");
    let mut r = csv::Reader::from_path(&csv).unwrap();
    let header = r.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap_or_else(|| panic!("column {n}"));
    let names = ["noise", "rho_ref", "scale", "splitter", "drift", "gain", "angle", "stray"];
    let (f, u, lo, hi) = (col("brdf_sr"), col("brdf_sigma_sr"), col("brdf_lo_sr"), col("brdf_hi_sr"));
    let mut angle_dominates = 0;
    for rec in r.records() {
        let rec = rec.unwrap();
        let x = |i: usize| rec[i].parse::<f64>().unwrap();
        let parts: Vec<f64> = names.iter().map(|n| x(col(&format!("u_{n}_sr")))).collect();
        let combined = parts.iter().map(|p| p * p).sum::<f64>().sqrt();
        assert!((combined / x(u) - 1.0).abs() < 1e-9);
        assert!((x(hi) - x(lo) - 4.0 * x(u)).abs() < 1e-9 * x(f).abs().max(1.0));
        angle_dominates += (parts[6] > parts.iter().cloned().fold(0.0, f64::max) * 0.999) as usize;
    }
    assert!(
        angle_dominates > 10,
        "on the mirror lobe's flanks the angle component dominates ({angle_dominates})"
    );

    // ALTA export: #VS 2 intervals that read back as the same uncertainties.
    let dat = dir.path().join("brdf.dat");
    let o = gonio(&["convert", csv.to_str().unwrap(), dat.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read_to_string(&dat).unwrap().contains("#VS 2"));
    let (a, b) = (formats::load(&csv, None).unwrap(), formats::load(&dat, None).unwrap());
    for (x, y) in a.observations.iter().zip(&b.observations) {
        let (sx, sy) = (x.sigma.unwrap(), y.sigma.unwrap());
        assert!((sx - sy).abs() <= 1e-9 * sx, "{sx} vs {sy}");
    }

    // Fit, weighted by the budget, and the coefficients from it.
    let fit_json = dir.path().join("fit.json");
    json(&[
        "fit",
        csv.to_str().unwrap(),
        "--model",
        "retro-phong",
        "--weights",
        "sigma",
        "--out",
        fit_json.to_str().unwrap(),
        "--json",
    ]);
    let coefficients = |extra: &[&str]| {
        let mut args = vec![
            "coefficients",
            "--fit",
            fit_json.to_str().unwrap(),
            "--set",
            "astm-e810",
            "--set",
            "en1436",
            "--json",
        ];
        args.extend_from_slice(extra);
        json(&args)
    };
    // EN 1436's 88.76° lies 28.76° beyond the scan's last incidence (60°),
    // farther than its finest spacing (15°): not measured, and the scan
    // that would measure it named; ASTM E810's −4°, 40° and 45° lie within
    // the spacing, and the fit (χ² consistent with the budget) carries them.
    let plain = coefficients(&[]);
    assert_eq!(plain["rl"]["provenance"], "not measured", "{}", plain["rl"]);
    assert!(plain["rl"]["value"].is_null());
    assert_eq!(plain["rl"]["measure_with"], "gonio scan --theta-i 88.76 --retro-rings 1.05");
    assert_eq!(plain["instrument"]["name"], "this head");
    assert_eq!(plain["wavelength_nm"].as_f64(), Some(633.0));
    for r in plain["ra"].as_array().unwrap() {
        assert!(r["value"].is_number(), "{r}");
    }
    let goodness = fit::file::read(&fit_json).unwrap().goodness.expect("the budget's σ judge the fit");
    assert!(goodness.p_value >= 0.01, "{goodness:?}");
    // Asked to, the fit carries R_L too, marked, and still covers the truth.
    let got = coefficients(&["--extrapolate"]);
    assert_eq!(got["rl"]["provenance"], "extrapolated");
    assert!(
        got["rl"]["basis"].as_str().unwrap().contains("extrapolated on request"),
        "{}",
        got["rl"]
    );
    let truth = json(&[
        "coefficients",
        "--model",
        "retro-phong",
        "--params",
        &Material::tape().params_string(),
        "--set",
        "astm-e810",
        "--set",
        "en1436",
        "--json",
    ]);
    let pairs = got["ra"]
        .as_array()
        .unwrap()
        .iter()
        .zip(truth["ra"].as_array().unwrap())
        .chain([(&got["rl"], &truth["rl"])]);
    for (g, t) in pairs {
        let (v, u, want) = (g["value"].as_f64().unwrap(), g["u"].as_f64().unwrap(), t["value"].as_f64().unwrap());
        assert!(u > 0.0 && (v - want).abs() <= 2.0 * u, "{g} vs truth {want}");
    }

    // Linear propagation against Monte Carlo (GUM S1), within 10 %.
    let f = fit::file::read(&fit_json).unwrap();
    let FittedBrdf::Model(material) = f.brdf else {
        panic!("a model's fit");
    };
    let src = Source::Model {
        material,
        covariance: f.covariance,
    };
    let reqs: Vec<_> = Set::AstmE810
        .requests()
        .into_iter()
        .step_by(11)
        .chain(Set::En1436.requests())
        .collect();
    for (r, c) in reqs.iter().zip(coefficients::compute(&src, &reqs).unwrap()) {
        let (lin, mc) = (c.estimate.u_params.unwrap(), src.monte_carlo_u(r, 4000, 3).unwrap());
        assert!((mc / lin - 1.0).abs() < 0.1, "{r:?}: linear {lin}, Monte Carlo {mc}");
    }

    // From the data directly: a retro ring holds α = 0.2° at β = 30°, so
    // the value is that sample's, and says so.
    let d = json(&[
        "coefficients",
        "--data",
        csv.to_str().unwrap(),
        "--alpha",
        "0.2",
        "--beta",
        "30",
        "--json",
    ]);
    let ra = &d["ra"][0];
    let near = &ra["nearest"][0];
    assert!(
        (near["theta_i_deg"].as_f64().unwrap() - 30.0).abs() < 0.01 && (near["theta_o_deg"].as_f64().unwrap() - 29.8).abs() < 0.01,
        "{ra}"
    );
    assert_eq!(ra["provenance"], "measured", "{ra}");
    let want = ra_at(&truth, 0.2, 30.0, 0.0)["value"].as_f64().unwrap();
    let v = ra["value"].as_f64().unwrap();
    assert!((v / want - 1.0).abs() < 0.05, "from data {v} vs truth {want}");
}

/// What each value rests on, told apart on a scan of the tape: the data
/// alone refuse an entrance angle they do not hold; the fit carries it,
/// marked extrapolated with the reason; a simulated material answers with
/// its own values, and `eval` with what the head's detector reads.
#[test]
fn values_say_what_they_rest_on_and_the_truth_is_at_hand() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    let o = gonio(&[
        "scan",
        "--sim",
        "--material",
        "retro-phong",
        "--reference-plate",
        "--theta-i",
        "30",
        "--theta-o",
        "0:60:6",
        "--dphi=-180:180:30",
        "--retro-rings",
        "0.2,0.5,1",
        "--retro-azimuths",
        "8",
        "--mirror-rings",
        "2",
        "--mirror-azimuths",
        "4",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = gonio(&["calibrate", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = out.join("calibrated.csv");
    let geometry = ["--alpha", "0.1,0.2,7", "--beta", "-4,30"];
    let mut args = vec!["coefficients", "--data", csv.to_str().unwrap(), "--json"];
    args.extend(geometry);
    let d = json(&args);
    let at = |v: &Value, a, b| ra_at(v, a, b, 0.0).clone();
    assert_eq!(at(&d, 0.2, 30.0)["provenance"], "measured", "{d}");
    // α 0.1°: the retro point, the 0.2° ring's view behind it and its two
    // neighbours all lie within the standard's 10′ aperture.
    let v = at(&d, 0.1, 30.0);
    assert_eq!(v["provenance"], "interpolated", "{v}");
    assert!(v["basis"].as_str().unwrap().contains("within the standard's 0.17° aperture"), "{v}");
    // θi 4°: one incidence measured (30°), so no spacing to lie within;
    // α 7° at 30°: among the grid's samples, but none within the aperture.
    for (a, b, rests_on) in [(0.2, -4.0, "not measured"), (7.0, 30.0, "extrapolated")] {
        let v = at(&d, a, b);
        assert_eq!(v["provenance"], rests_on, "{v}");
        assert!(v["value"].is_null(), "the data alone refuse it: {v}");
    }
    let fit_json = dir.path().join("fit.json");
    json(&[
        "fit",
        csv.to_str().unwrap(),
        "--model",
        "retro-phong",
        "--out",
        fit_json.to_str().unwrap(),
        "--json",
    ]);
    let mut args = vec!["coefficients", "--fit", fit_json.to_str().unwrap(), "--json"];
    args.extend(geometry);
    // A fit of one incidence does not reach 26° away unasked.
    let f = json(&args);
    let v = at(&f, 0.2, -4.0);
    assert_eq!(v["provenance"], "not measured", "{v}");
    assert!(
        v["value"].is_null() && v["basis"].as_str().unwrap().contains("was not measured"),
        "{v}"
    );
    assert_eq!(v["measure_with"], "gonio scan --theta-i 4 --retro-rings 0.2");
    args.push("--extrapolate");
    let f = json(&args);
    let v = at(&f, 0.2, -4.0);
    assert_eq!(v["provenance"], "extrapolated", "{v}");
    assert!(
        v["value"].as_f64().unwrap() > 0.0 && v["basis"].as_str().unwrap().contains("extrapolated on request"),
        "{v}"
    );
    assert_eq!(v["model"], "retro-phong");
    let text_of = |extra: &[&str]| {
        let mut args = vec![
            "coefficients",
            "--fit",
            fit_json.to_str().unwrap(),
            "--alpha",
            "0.2",
            "--beta",
            "-4",
        ];
        args.extend_from_slice(extra);
        text(&gonio(&args))
    };
    let out_text = text_of(&[]);
    assert!(
        out_text.contains("NOT MEASURED") && out_text.contains("measure it: gonio scan --theta-i 4 --retro-rings 0.2"),
        "{out_text}"
    );
    let out_text = text_of(&["--extrapolate"]);
    assert!(
        out_text.contains("EXTRAPOLATED") && out_text.contains("carried by retro-phong"),
        "{out_text}"
    );

    let truth = json(&[
        "coefficients",
        "--material",
        "glass-beads",
        "--alpha",
        "0.2",
        "--beta",
        "-4",
        "--json",
    ]);
    let v = ra_at(&truth, 0.2, -4.0, 0.0)["value"].as_f64().unwrap();
    assert!((v - 6.13).abs() < 0.01, "the glass beads' own R_A(0.2°, −4°): {v}");
    let e = json(&[
        "eval",
        "--material",
        "glass-beads",
        "--theta-i",
        "30",
        "--theta-o",
        "29.8",
        "--dphi",
        "0",
        "--json",
    ]);
    let (fr, seen) = (e["fr"].as_f64().unwrap(), e["fr_seen"].as_f64().unwrap());
    assert!(
        seen > fr * 1.01,
        "on the ring's inner flank the detector's field reads high: {fr} vs {seen}"
    );
}
