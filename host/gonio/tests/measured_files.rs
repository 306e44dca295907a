//! Files the project did not write, as a new user hands them to `gonio`:
//! a measured tape in ALTA's format that stores `f_r·cosθo` out to the
//! horizon (`tests/data/tape-frcos.dat`), binary and oversized files, and
//! geometries measured twice.

use serde_json::Value;
use std::path::{Path, PathBuf};
mod common;
use common::{gonio, text};

fn tape() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/tape-frcos.dat")
}

/// The largest value of an ALTA file's single output column.
fn largest_value(alta: &str) -> f64 {
    alta.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().nth(3).unwrap().parse::<f64>().unwrap())
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn a_tape_stored_as_fr_cos_loses_its_grazing_rows_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let fr = dir.path().join("fr.dat");
    let o = gonio(&["convert", tape().to_str().unwrap(), fr.to_str().unwrap(), "--units", "fr"]);
    assert!(o.status.success(), "{}", text(&o));
    let said = text(&o);
    assert!(
        said.contains("63 of 2277 rows dropped: their θo is beyond 89.9°"),
        "the drop is counted and explained: {said}"
    );
    // The tape's peak, its retro and mirror lobes together at normal
    // incidence, is 42 sr⁻¹ and its floor; the rows at 90° were 10¹³.
    let peak = largest_value(&std::fs::read_to_string(&fr).unwrap());
    assert!((42.0..42.1).contains(&peak), "largest f_r {peak}");

    let fit = dir.path().join("fit.json");
    let o = gonio(&[
        "fit",
        tape().to_str().unwrap(),
        "--model",
        "retro-phong",
        "--out",
        fit.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["samples"], 2277 - 63 - 245 + 35, "{v}");
    assert_eq!(v["units"], "fr-cos");

    let o = gonio(&[
        "plot",
        tape().to_str().unwrap(),
        "--out",
        dir.path().join("plots").to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = gonio(&["export", fit.to_str().unwrap(), dir.path().join("tape.brdf").to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn binary_and_oversized_files_are_refused_by_what_they_are() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, bytes: &[u8]| {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let o = gonio(&["fit", p.to_str().unwrap(), "--model", "lambert", "--json"]);
        assert!(!o.status.success());
        let v: Value = serde_json::from_slice(&o.stdout).unwrap_or_else(|_| panic!("{}", text(&o)));
        v["error"].as_str().unwrap().to_string()
    };
    let zeros = vec![0u8; 1 << 20];
    assert!(run("zeros.dat", &zeros).contains("byte 0 is NUL: binary content"));
    assert!(run("zeros.csv", &zeros).contains("byte 0 is NUL: binary content"));
    let mut late = b"theta_i_deg,theta_o_deg,dphi_deg,brdf_sr\n".to_vec();
    late.extend(b"10,20,30,1\n".repeat(200));
    late.push(0);
    assert!(run("late.csv", &late).contains("line 202: byte 2241 is NUL"));
    let long = format!("#DIM 3 1\n{}\n", "1 ".repeat(40_000));
    assert!(run("long.dat", long.as_bytes()).contains("line 2: longer than 64 KiB"));
    let mut many = b"theta_i_deg,theta_o_deg,dphi_deg,brdf_sr\n".to_vec();
    many.extend(b"10,20,30,1\n".repeat(1_000_001));
    assert!(run("many.csv", &many).contains("more than 1000000 samples"));
}

#[test]
fn repeated_geometries_are_merged_with_their_spread() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("twice.csv");
    let mut csv = String::from("theta_i_deg,theta_o_deg,dphi_deg,brdf_sr,brdf_sigma_sr\n");
    for k in 0..30 {
        csv += &format!("30,{},0,1.0,0.01\n", 2 * k);
    }
    csv += "30,10,0,3.0,0.01\n";
    std::fs::write(&p, csv).unwrap();
    let o = gonio(&["fit", p.to_str().unwrap(), "--model", "lambert", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let said = text(&o);
    assert!(
        said.contains("1 geometry appears more than once (2 of 31 rows): each is merged to the mean of its values, with their spread added to its uncertainty; the widest spread, at θi 30.00°, θo 10.00°, Δφ 0.00°, is a factor 3.000"),
        "{said}"
    );
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["samples"], 30);
}

/// The rational function through every ±0.5 sr⁻¹ segment of the measured
/// tape: refused before (the grazing rows, then no function held by
/// single precision's margin up to degree 8), it is found held in double
/// precision with ALTA's count (126 coefficients, in ALTA's view plane),
/// single precision tried up to twice as many, and said so.
#[test]
fn the_rational_function_passes_through_a_measured_tape() {
    let o = gonio(&[
        "fit",
        tape().to_str().unwrap(),
        "--model",
        "rational",
        "--segments",
        "abs:0.5",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["worst_violation"], 0.0, "{v}");
    // In the file's own quantity, as ALTA and the paper fit it.
    assert_eq!(v["quantity"], "fr-cos", "{v}");
    assert_eq!(v["precision"], "double", "{v}");
    let coefficients = v["coefficients"].as_u64().unwrap();
    assert!(coefficients <= 126, "{v}");
    let attempts = v["attempts"].as_array().unwrap();
    assert!(
        attempts
            .iter()
            .any(|a| a["single_precision"] == true && a["coefficients"] == (2 * coefficients).min(330) && a["feasible"] == false),
        "single precision was tried up to twice the count: {v}"
    );
}

/// `--densify`: the paper's path (§6.A), a grid between the samples fitted
/// instead of them, with how many of the measured segments the function
/// still holds; the grid is refused below its finest step.
#[test]
fn a_densified_tape_is_fitted_on_its_grid_and_checked_on_its_samples() {
    let tape = tape();
    let fit = |step: &str| {
        gonio(&[
            "fit",
            tape.to_str().unwrap(),
            "--model",
            "rational",
            "--segments",
            "abs:2",
            "--densify",
            step,
            "--json",
        ])
    };
    let o = fit("3");
    assert!(o.status.success(), "{}", text(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let d = &v["densified"];
    let measured = &d["measured"];
    assert_eq!(d["step_deg"], 3.0, "{v}");
    assert_eq!(v["samples"], d["points"], "the grid is what was fitted: {v}");
    assert!(d["points"].as_u64().unwrap() > measured["of"].as_u64().unwrap(), "{v}");
    assert!(measured["held"].as_u64().unwrap() <= measured["of"].as_u64().unwrap(), "{v}");
    assert!(measured["worst"].as_f64().unwrap() >= 0.0, "{v}");
    let o = fit("0.01");
    assert!(!o.status.success());
    assert!(text(&o).contains("at least 0.1"), "{}", text(&o));
}
