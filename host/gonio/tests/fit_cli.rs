//! `gonio fit`, `compare`, `eval` and `dhr` as a user runs them, on ALTA and
//! CSV files written here from a known material.

use gonio_analysis::fit::{Dataset, Observation, Units};
use gonio_analysis::formats::alta;
use gonio_brdf::{Material, ModelId};
use serde_json::Value;
use std::path::{Path, PathBuf};
mod common;
use common::{gonio, text};

/// Noise-free samples of a material on the Belcour grid (θo < 90°), the
/// view along the normal once per incidence (its azimuths are one geometry).
fn dataset(m: &Material, units: Units) -> Dataset {
    let mut observations = Vec::new();
    for ti in [15.0f64, 30.0, 60.0] {
        for k in 0..30 {
            for j in (0..36).filter(|&j| k > 0 || j == 18) {
                let mut o = Observation {
                    theta_i: ti.to_radians(),
                    theta_o: (3.0 * k as f64).to_radians(),
                    dphi: (-180.0 + 10.0 * j as f64).to_radians(),
                    value: 0.0,
                    sigma: None,
                    shared: Default::default(),
                };
                o.value = m.eval(&o.directions()) * o.unit_factor(units);
                observations.push(o);
            }
        }
    }
    Dataset {
        units,
        observations,
        metadata: vec!["material: synthetic".into()],
        units_stated: true,
        warnings: Vec::new(),
        instrument: gonio_analysis::instrument::Instrument::Unknown,
    }
}

fn tape() -> Material {
    Material::parse(ModelId::RetroPhong, "kd=0.62,n=24,k1=0.158,k2=0.0415,k3=0.00133,k4=5.47").unwrap()
}

fn write_alta(dir: &Path, m: &Material, units: Units) -> PathBuf {
    let p = dir.join("data.dat");
    std::fs::write(&p, alta::write(&dataset(m, units))).unwrap();
    p
}

#[test]
fn fit_json_has_the_contract_fields_and_recovers_the_material() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_alta(dir.path(), &tape(), Units::FrCos);
    let o = gonio(&["fit", file.to_str().unwrap(), "--model", "retro-phong", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "model",
        "parametrization",
        "params",
        "stderr",
        "rmse",
        "nrmse",
        "ncc",
        "l2",
        "samples",
        "seconds",
    ] {
        assert!(v.get(key).is_some(), "missing {key}: {v}");
    }
    assert_eq!(v["model"], "retro-phong");
    assert_eq!(v["parametrization"], "view");
    assert_eq!(v["samples"], 3 * (29 * 36 + 1));
    let names: Vec<&String> = v["params"].as_object().unwrap().keys().collect();
    assert_eq!(names, ["kd", "n", "k1", "k2", "k3", "k4"]);
    // The covariance (for `gonio coefficients`): its diagonal is the stderr squared.
    for (i, name) in names.iter().enumerate() {
        let var = v["covariance"][i][i].as_f64().unwrap();
        let se = v["stderr"][name.as_str()].as_f64().unwrap();
        assert!((var.sqrt() / se - 1.0).abs() < 1e-12, "{name}: {var} vs {se}²");
    }
    for (name, want) in ["kd", "n", "k1", "k2", "k3", "k4"].iter().zip(tape().params) {
        let got = v["params"][name].as_f64().unwrap();
        assert!((got - want).abs() <= 1e-6 * want.abs(), "{name}: {got} vs {want}");
    }
    assert!(v["ncc"].as_f64().unwrap() > 0.999_999);
    // Unweighted: no χ²; the correlations of the free parameters are there.
    assert!(v["goodness"].is_null());
    assert_eq!(v["correlation"]["params"].as_array().unwrap().len(), 6);
    assert_eq!(v["correlation"]["matrix"][2][2], 1.0);
}

#[test]
fn fixed_parameters_stay_put_and_held_out_angles_are_predicted() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_alta(dir.path(), &tape(), Units::Fr);
    let o = gonio(&[
        "fit",
        file.to_str().unwrap(),
        "--model",
        "retro-phong",
        "--fix",
        "kd=0.62",
        "--holdout-theta-i",
        "30",
        "--retro-only",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["params"]["kd"], 0.62);
    assert_eq!(v["stderr"]["kd"], Value::Null);
    // Retro half-space (|Δφ| ≤ 90°: 19 of 36 azimuths) of θi 15° and 60°,
    // and the view along the normal.
    assert_eq!(v["samples"], 2 * (29 * 19 + 1));
    assert!(v["holdout"]["ncc"].as_f64().unwrap() > 0.9999, "{v}");
    // An angle the file does not hold is named with those it does, even
    // where the restrictions leave none.
    let f = file.to_str().unwrap();
    for args in [
        vec!["fit", f, "--model", "lambert", "--holdout-theta-i", "45"],
        vec!["fit", f, "--model", "lambert", "--theta-i", "45"],
    ] {
        let o = gonio(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(text(&o).contains("holds θi = 15°, 30°, 60°"), "{args:?}: {}", text(&o));
    }
}

#[test]
fn convert_writes_alta_that_reads_back_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("brdf.csv");
    let mut w = String::from("theta_i_deg,theta_o_deg,dphi_deg,brdf_sr,brdf_sigma_sr\n");
    for (k, v) in [0.123456789012345f64, 7.5e-3, 41.25].iter().enumerate() {
        w.push_str(&format!("30,{},{},{v},0.001\n", 10 * k + 5, 40 * k as i32 - 40));
    }
    std::fs::write(&csv, w).unwrap();
    let dat = dir.path().join("out.dat");
    let o = gonio(&["convert", csv.to_str().unwrap(), dat.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let back = alta::parse(&std::fs::read_to_string(&dat).unwrap()).unwrap();
    let values: Vec<f64> = back.observations.iter().map(|o| o.value).collect();
    assert_eq!(values, [0.123456789012345, 7.5e-3, 41.25]);
    assert!(back.metadata.iter().any(|m| m.contains("converted by gonio")));
    // Converted again and again: the values stay exact (shortest round-trip
    // numbers), the angles and σ within the rounding of ALTA's projected
    // coordinates and k = 2 interval, and the header grows by one line of
    // provenance per pass, nothing else.
    let mut last = dat.clone();
    for pass in 2..=4 {
        let next = dir.path().join(format!("out{pass}.dat"));
        let o = gonio(&["convert", last.to_str().unwrap(), next.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
        let text = std::fs::read_to_string(&next).unwrap();
        let again = alta::parse(&text).unwrap();
        for (a, b) in back.observations.iter().zip(&again.observations) {
            assert_eq!(a.value, b.value, "pass {pass}");
            for (x, y) in [(a.theta_i, b.theta_i), (a.theta_o, b.theta_o), (a.dphi, b.dphi)] {
                assert!((x - y).abs() < 1e-14, "pass {pass}: angle {x} → {y}");
            }
            let (s, t) = (a.sigma.unwrap(), b.sigma.unwrap());
            assert!((s - t).abs() < 1e-12 * s, "pass {pass}: σ {s} → {t}");
        }
        assert_eq!(text.matches("# confidence:").count(), 1, "pass {pass}");
        assert_eq!(
            again.metadata.len(),
            back.metadata.len() + pass - 1,
            "pass {pass}: {:?}",
            again.metadata
        );
        last = next;
    }
    let o = gonio(&["convert", csv.to_str().unwrap(), dat.to_str().unwrap(), "--units", "fr-cos"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::read_to_string(&dat)
        .unwrap()
        .contains("#PARAM_OUT INV_STERADIAN_COSINE_FACTOR"));
}

/// Plot structure, not pixels: every picture in both formats, not blank, and
/// one curve (plus its legend line) per fit in the incidence-plane plots.
#[test]
fn fit_and_plot_draw_every_picture() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_alta(dir.path(), &tape(), Units::Fr);
    let f = file.to_str().unwrap();
    let (fit_a, fit_b) = (dir.path().join("a.json"), dir.path().join("b.json"));
    let plots = dir.path().join("fit-plots");
    let o = gonio(&[
        "fit",
        f,
        "--model",
        "retro-phong",
        "--out",
        fit_a.to_str().unwrap(),
        "--plot",
        plots.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    // --bsdf: the renderer's file as well, beside the fit's one JSON object.
    let bsdf = dir.path().join("b.bsdf");
    let o = gonio(&[
        "fit",
        f,
        "--model",
        "lambert",
        "--out",
        fit_b.to_str().unwrap(),
        "--bsdf",
        bsdf.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    serde_json::from_slice::<serde_json::Value>(&o.stdout).expect("one JSON object");
    assert!(std::fs::read(&bsdf).unwrap().starts_with(b"tensor_file\0"));
    // The fit as a BRDF Explorer shader (its GLSL is checked in tests/tests/brdf_export.rs).
    let brdf = dir.path().join("a.brdf");
    let o = gonio(&["export", fit_a.to_str().unwrap(), brdf.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let shader = std::fs::read_to_string(&brdf).unwrap();
    assert!(shader.starts_with("analytic\n") && shader.contains("vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"));
    for name in ModelId::RetroPhong.param_names() {
        assert!(shader.contains(&format!("\nfloat {name} ")), "parameter line of {name}");
    }
    let both = dir.path().join("both");
    let o = gonio(&[
        "plot",
        f,
        "--out",
        both.to_str().unwrap(),
        "--fit",
        fit_a.to_str().unwrap(),
        "--fit",
        fit_b.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    for (d, fits) in [(&plots, 1), (&both, 2)] {
        for ti in ["15", "30", "60"] {
            for kind in ["plane", "cuts", "hemisphere", "residuals"] {
                let png = d.join(format!("{kind}-{ti}.png"));
                let svg = d.join(format!("{kind}-{ti}.svg"));
                // A blank 720×720 PNG compresses to a few kB.
                assert!(std::fs::metadata(&png).unwrap().len() > 20_000, "{} too small", png.display());
                assert!(std::fs::metadata(&svg).unwrap().len() > 5_000, "{}", svg.display());
            }
            let svg = std::fs::read_to_string(d.join(format!("plane-{ti}.svg"))).unwrap();
            for (k, color) in ["#D62728", "#1F77B4"].iter().enumerate() {
                let curves = svg
                    .matches(&format!("<polyline fill=\"none\" opacity=\"1\" stroke=\"{color}\""))
                    .count();
                assert_eq!(curves, if k < fits { 2 } else { 0 }, "θi {ti}: curves of fit {k}");
            }
            assert!(
                svg.contains("\nretro\n") && svg.contains("\nmirror\n"),
                "retro and mirror directions marked"
            );
        }
    }
}

/// The comparison as JSON, as a table, and as `report.html` (with every fit
/// and its shader beside it); the rational function beside the models when
/// its segments can be had, and why not when they cannot.
#[test]
fn compare_lists_every_model() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_alta(dir.path(), &tape(), Units::Fr);
    // The file has no σ, so the rational function's default segments
    // cannot be had: a note says so, and the models stand.
    let o = gonio(&["compare", file.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let models: Vec<&str> = v["fits"].as_array().unwrap().iter().map(|f| f["model"].as_str().unwrap()).collect();
    assert_eq!(models, ModelId::ALL.map(|m| m.name()));
    let why = v["unfitted"][0].as_str().unwrap_or_else(|| panic!("{}", v["unfitted"]));
    assert!(why.contains("rational") && why.contains("abs:WIDTH"), "{why}");
    // With relative segments it is fitted, ranked and reported as a model is.
    let report = dir.path().join("report");
    // Degree 6 at most: degree 8 costs a minute in a test build.
    let segments = ["--segments", "rel:0.2", "--max-degree", "6"];
    let o = gonio(&[&["compare", file.to_str().unwrap(), "--json"][..], &segments].concat());
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let fits = v["fits"].as_array().unwrap();
    assert_eq!(fits.len(), ModelId::ALL.len() + 1, "{v}");
    assert_eq!(v["unfitted"], serde_json::json!([]));
    let rational = fits.iter().find(|f| f["model"] == "rational").unwrap();
    assert_eq!(rational["worst_violation"], 0.0);
    assert!(rational["rank"]["aic"].is_u64() && rational["bic"].is_f64(), "{rational}");
    // Every sample within 20 % of its value.
    let peak = dataset(&tape(), Units::Fr).observations.iter().map(|o| o.value).fold(0.0, f64::max);
    assert!(rational["linf"].as_f64().unwrap() <= 0.2 * peak, "{rational}");
    let best = fits
        .iter()
        .min_by(|a, b| a["rmse"].as_f64().unwrap().total_cmp(&b["rmse"].as_f64().unwrap()))
        .unwrap();
    assert_eq!(best["model"], "retro-phong");
    let table = gonio(
        &[
            &["compare", file.to_str().unwrap(), "--report", report.to_str().unwrap()][..],
            &segments,
        ]
        .concat(),
    );
    assert!(
        text(&table).contains("NRMSE") && text(&table).contains("five-param") && text(&table).contains("rational"),
        "{}",
        text(&table)
    );
    let mut names = ModelId::ALL.map(|m| m.name()).to_vec();
    names.push("rational");
    let html = common::check_report(&report, &names, &["15", "30", "60"]);
    assert!(
        html.contains("fewest terms that passes through every sample"),
        "the rational row is explained"
    );
    // Another instrument's file without σ: adequacy is not judged, no
    // value rests on a model, and nothing of this head is claimed for it.
    assert!(html.contains("<b>Adequacy cannot be judged</b>"), "{html}");
    assert!(html.contains("whose apertures are not known") && html.contains("the data do not state"));
    assert!(!html.contains("0.39°") && !html.contains("633 nm") && !html.contains("<small>extrapolated ("));
    let fit_json = report.join("fits").join("retro-phong.json");
    let c: Value = serde_json::from_slice(
        &gonio(&[
            "coefficients",
            "--fit",
            fit_json.to_str().unwrap(),
            "--set",
            "astm-e810",
            "--rl",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    assert_eq!(c["instrument"]["name"], "unknown", "{c}");
    assert!(c["wavelength_nm"].is_null());
    for r in c["ra"].as_array().unwrap().iter().chain([&c["rl"]]) {
        let on_data = r["provenance"] == "measured" || r["provenance"] == "interpolated";
        assert_eq!(r["value"].is_number(), on_data, "{r}");
        assert!(r.get("u_aperture").is_none() || r["u_aperture"] == 0.0, "not carried: {r}");
    }
    // Stated, the apertures and wavelength are the file's own.
    let o = gonio(&[
        "fit",
        file.to_str().unwrap(),
        "--model",
        "lambert",
        "--instrument-source-deg",
        "0.1",
        "--instrument-receiver-deg",
        "0.2",
        "--instrument-wavelength-nm",
        "550",
        "--out",
        dir.path().join("l.json").to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let c: Value = serde_json::from_slice(
        &gonio(&[
            "coefficients",
            "--fit",
            dir.path().join("l.json").to_str().unwrap(),
            "--rl",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    assert_eq!(c["wavelength_nm"].as_f64(), Some(550.0), "{c}");
    assert_eq!(c["instrument"]["apertures"]["receiver_deg"].as_f64(), Some(0.2));
    // Best first.
    let models = &html[html.find("<h2>Models</h2>").unwrap()..];
    let first_row = models.find("<td class=\"l\">").map(|i| &models[i..i + 40]).unwrap();
    assert!(first_row.contains("retro-phong"), "{first_row}");
    // A report is not overwritten unless asked.
    let again = gonio(&["compare", file.to_str().unwrap(), "--report", report.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(1));
    assert!(text(&again).contains("already holds a report"), "{}", text(&again));
    let forced = gonio(&[
        "compare",
        file.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--force",
        "--json",
    ]);
    assert!(forced.status.success(), "{}", text(&forced));
    // Written again without the rational function: its files from the
    // first report are gone, the models' are the new ones.
    assert!(!report.join("fits/rational.json").exists() && !report.join("fits/rational.brdf").exists());
    assert!(report.join("fits/retro-phong.json").is_file());
}

#[test]
fn eval_and_dhr() {
    let o = gonio(&[
        "eval",
        "--model",
        "lambert",
        "--params",
        "kd=0.5",
        "--theta-i",
        "30",
        "--theta-o",
        "10",
        "--dphi",
        "-40",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["fr"].as_f64().unwrap() - 0.5 / std::f64::consts::PI).abs() < 1e-15);
    let o = gonio(&["dhr", "--model", "lambert", "--params", "kd=0.5", "--theta-i", "45", "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["dhr"].as_f64().unwrap() - 0.5).abs() < 1e-4, "{v}");
    assert_eq!(v["energy_conserving"], true);
    let o = gonio(&[
        "dhr",
        "--model",
        "retro-phong",
        "--params",
        &tape().params_string(),
        "--theta-i",
        "60",
        "--json",
    ]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["kd_ks_kr"].as_f64().unwrap() < 1.0, "{v}");
}

#[test]
fn mistakes_name_the_valid_choices_or_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let good = write_alta(dir.path(), &tape(), Units::Fr);
    let g = good.to_str().unwrap();
    let bad = |name: &str, content: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, content).unwrap();
        p.to_str().unwrap().to_string()
    };
    let header = "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n#VS 0\n";
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["fit".into(), g.into(), "--model".into(), "phong".into()],
            "valid models: lambert, retro-phong",
        ),
        (
            vec![
                "fit".into(),
                g.into(),
                "--model".into(),
                "lambert".into(),
                "--fix".into(),
                "ks=1".into(),
            ],
            "valid: kd",
        ),
        (
            vec![
                "eval".into(),
                "--model".into(),
                "lambert".into(),
                "--params".into(),
                "kd=1,q=2".into(),
                "--theta-i".into(),
                "1".into(),
                "--theta-o".into(),
                "1".into(),
                "--dphi".into(),
                "0".into(),
            ],
            "valid: kd",
        ),
        (
            vec![
                "fit".into(),
                bad(
                    "dim.dat",
                    "#DIM 2 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n0.1 0.2 0.3\n",
                ),
                "--model".into(),
                "lambert".into(),
            ],
            "line 4: #DIM says 2 inputs",
        ),
        (
            vec![
                "fit".into(),
                bad("nan.dat", &format!("{header}0.1 0.2 0.3 0.5\n0.1 0.2 NaN 0.5\n")),
                "--model".into(),
                "lambert".into(),
            ],
            "line 6: `NaN` is not a finite number",
        ),
        (
            vec![
                "fit".into(),
                bad("word.dat", &format!("{header}0.1 0.2 abc 0.5\n")),
                "--model".into(),
                "lambert".into(),
            ],
            "line 5: `abc` is not a number",
        ),
        (
            vec![
                "fit".into(),
                bad("nohead.dat", "0.1 0.2 0.3 0.5\n"),
                "--model".into(),
                "lambert".into(),
            ],
            "line 1: data before any #PARAM_IN",
        ),
        (
            vec!["fit".into(), bad("empty.dat", ""), "--model".into(), "lambert".into()],
            "no data lines",
        ),
        (
            vec!["fit".into(), bad("empty.csv", ""), "--model".into(), "lambert".into()],
            "line 1: the file is empty",
        ),
        (
            vec![
                "fit".into(),
                bad("bad.csv", "theta_i_deg,theta_o_deg,dphi_deg,brdf_sr\n30,10,0,0.2\n30,x,0,0.2\n"),
                "--model".into(),
                "lambert".into(),
            ],
            "line 3: column `theta_o_deg`: `x` is not a number",
        ),
        (
            vec!["fit".into(), "/nonexistent.dat".into(), "--model".into(), "lambert".into()],
            "cannot read /nonexistent.dat",
        ),
        (
            vec![
                "dhr".into(),
                "--model".into(),
                "lambert".into(),
                "--params".into(),
                "kd=1".into(),
                "--theta-i".into(),
                "95".into(),
            ],
            "must be in [0, 90)",
        ),
    ];
    for (args, says) in cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = gonio(&args);
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {msg}");
        assert!(msg.contains(says), "{args:?}: `{msg}` does not say `{says}`");
        assert!(!msg.contains("panicked"), "{msg}");
    }
}

/// An ALTA file without `#PARAM_OUT` (ALTA's UNKNOWN_OUTPUT) is
/// fitted, with a warning that says what was assumed; `--units` says what
/// the values are, and the fit follows it.
#[test]
fn a_file_that_does_not_say_its_units_is_fitted_as_told() {
    let dir = tempfile::tempdir().unwrap();
    let m = Material::parse(ModelId::Lambert, "kd=0.5").unwrap();
    let written = alta::write(&dataset(&m, Units::FrCos));
    let bare: String = written
        .lines()
        .filter(|l| !l.starts_with("#PARAM_OUT"))
        .map(|l| format!("{l}\n"))
        .collect();
    let p = dir.path().join("bare.dat");
    std::fs::write(&p, bare).unwrap();
    let f = p.to_str().unwrap();
    let o = gonio(&["fit", f, "--model", "lambert", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("warning") && stderr.contains("--units fr-cos"), "{stderr}");
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["warnings"].as_array().is_some_and(|w| !w.is_empty()));
    assert!(
        v["ncc"].as_f64().unwrap() < 0.999,
        "read as f_r, cos-weighted values do not fit a Lambertian exactly"
    );
    let o = gonio(&["fit", f, "--model", "lambert", "--units", "fr-cos", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["params"]["kd"].as_f64().unwrap() - 0.5).abs() < 1e-9, "{v}");
}

/// Bad input: no data, all-zero values, fewer samples than
/// parameters are errors; negative values and a single incidence angle are
/// warnings that name the problem; never a panic.
#[test]
fn doubtful_data_is_refused_or_named() {
    let dir = tempfile::tempdir().unwrap();
    let header = "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n";
    let write = |name: &str, body: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, format!("{header}{body}")).unwrap();
        p.to_str().unwrap().to_string()
    };
    let rows = |f: &dyn Fn(usize) -> f64| -> String {
        (0..40)
            .map(|k| format!("{} {} 0.1 {}\n", 0.2 + 0.3 * (k % 3) as f64, 0.02 * k as f64, f(k)))
            .collect()
    };
    for (file, model, says) in [
        (write("empty.dat", ""), "lambert", "no data lines"),
        (write("zero.dat", &rows(&|_| 0.0)), "lambert", "every value is zero"),
        (
            write("few.dat", "0.2 0.1 0.1 1\n0.5 0.1 0.1 1\n"),
            "retro-phong",
            "2 samples for 6 free parameters",
        ),
    ] {
        let o = gonio(&["fit", &file, "--model", model]);
        let msg = text(&o);
        assert_eq!(o.status.code(), Some(1), "{file}: {msg}");
        assert!(
            msg.contains(says) && !msg.contains("panicked"),
            "{file}: `{msg}` does not say `{says}`"
        );
    }
    for (file, says) in [
        (
            write("negative.dat", &rows(&|k| if k % 5 == 0 { -0.01 } else { 0.2 })),
            "8 of 40 values are negative",
        ),
        (
            write(
                "single.dat",
                &(0..40).map(|k| format!("0.5 {} 0.1 0.2\n", 0.02 * k as f64)).collect::<String>(),
            ),
            "one incidence angle only",
        ),
    ] {
        let o = gonio(&["fit", &file, "--model", "lambert"]);
        let msg = text(&o);
        assert!(o.status.success(), "{file}: {msg}");
        assert!(
            msg.contains("warning") && msg.contains(says),
            "{file}: `{msg}` does not say `{says}`"
        );
    }
}

/// The search box holds data in relative units (its amplitudes
/// follow the data's scale), `--bounds` replaces it, and a fit that ends on
/// its edge says so (`at_bound` in JSON, a warning in text).
#[test]
fn search_boxes_follow_the_data_and_say_when_they_bind() {
    let dir = tempfile::tempdir().unwrap();
    // A Lambertian in counts: kd = 500, far outside the calibrated box.
    let m = Material::parse(ModelId::Lambert, "kd=500").unwrap();
    let p = dir.path().join("counts.dat");
    std::fs::write(&p, alta::write(&dataset(&m, Units::Fr))).unwrap();
    let f = p.to_str().unwrap();
    let o = gonio(&["fit", f, "--model", "lambert", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["params"]["kd"].as_f64().unwrap() / 500.0 - 1.0).abs() < 1e-9, "{v}");
    assert_eq!(v["at_bound"], serde_json::json!([]));
    // A box that excludes it: the fit ends on its edge and says so.
    let o = gonio(&["fit", f, "--model", "lambert", "--bounds", "kd=0:100", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["at_bound"], serde_json::json!(["kd"]));
    assert!((v["params"]["kd"].as_f64().unwrap() - 100.0).abs() < 1e-6);
    let o = gonio(&["fit", f, "--model", "lambert", "--bounds", "kd=0:100"]);
    assert!(text(&o).contains("warning: kd ended on the edge of its search box"), "{}", text(&o));
    for (bad, says) in [
        ("kd=1", "not NAME=LO:HI"),
        ("kd=3:1", "LO < HI"),
        ("zz=0:1", "unknown parameter `zz`"),
    ] {
        let o = gonio(&["fit", f, "--model", "lambert", "--bounds", bad]);
        assert_eq!(o.status.code(), Some(1));
        assert!(text(&o).contains(says), "{bad}: {}", text(&o));
    }
    // compare: every model takes the names it has; AIC/BIC ranks beside RMSE's.
    let o = gonio(&["compare", f, "--bounds", "kd=0:1000,n=1:100", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let rows = serde_json::from_slice::<Value>(&o.stdout).unwrap()["fits"]
        .as_array()
        .unwrap()
        .clone();
    let models = ModelId::ALL.len();
    assert_eq!(rows.len(), models);
    let mut ranks: Vec<u64> = rows.iter().map(|r| r["rank"]["aic"].as_u64().unwrap()).collect();
    ranks.sort();
    assert_eq!(ranks, (1..=models as u64).collect::<Vec<u64>>());
    assert!(rows.iter().all(|r| r["at_bound"].is_array() && r["bic"].is_f64()));
}

/// With `--weights sigma` the fit says whether it is adequate within the
/// samples' uncertainties: χ², degrees of freedom, p-value, and a verdict.
#[test]
fn a_sigma_weighted_fit_reports_its_chi2() {
    let dir = tempfile::tempdir().unwrap();
    let mut data = dataset(&tape(), Units::Fr);
    data.observations
        .iter_mut()
        .for_each(|o| o.sigma = Some(0.01 * o.value.abs().max(1e-6)));
    let p = dir.path().join("sigma.dat");
    std::fs::write(&p, alta::write(&data)).unwrap();
    let f = p.to_str().unwrap();
    // Exact data: χ² far below its degrees of freedom, the σ overstated.
    let o = gonio(&["fit", f, "--model", "retro-phong", "--weights", "sigma"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("degrees of freedom") && text(&o).contains("overstated"),
        "{}",
        text(&o)
    );
    let o = gonio(&["fit", f, "--model", "lambert", "--weights", "sigma", "--json"]);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["goodness"]["dof"], 3 * (29 * 36 + 1) - 1);
    assert!(
        v["goodness"]["reduced_chi2"].as_f64().unwrap() > 10.0 && v["goodness"]["p_value"].as_f64().unwrap() < 1e-12,
        "{v}"
    );
    let t = gonio(&["fit", f, "--model", "lambert", "--weights", "sigma"]);
    assert!(text(&t).contains("misses the data by more than their uncertainty"), "{}", text(&t));
}
