//! The reference-plate calibration on the simulated head: reference plate, laser
//! drift of ±5 % during the scan, monitor readings, `gonio calibrate`, and
//! the calibrated BRDF against the virtual material's truth.

use gonio_analysis::calibration::{Budget, Calibration};
use gonio_brdf::{Directions, Material};
use gonio_scan_dir::samples::{self, Row};
use std::path::Path;
mod common;
use common::{gonio, text};

fn truth(r: &Row) -> f64 {
    Material::tape().eval(&Directions::from_degrees(
        r.theta_i_deg as f64,
        r.theta_o_deg as f64,
        r.dphi_deg as f64,
    ))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median |calibrated/truth − 1| over the usable samples of a calibration.
fn median_error(cal: &Calibration, rows: &[Row]) -> f64 {
    let (out, _) = cal.apply(rows, &Budget::default());
    median(
        out.iter()
            .filter(|c| c.usable)
            .map(|c| (c.brdf_sr / truth(&c.raw) - 1.0).abs())
            .collect(),
    )
}

#[test]
fn calibrated_brdf_matches_the_truth_with_the_laser_drifting() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tape");
    let o = gonio(&[
        "scan",
        "--sim",
        "--material",
        "retro-phong",
        "--laser-drift",
        "0.05",
        "--reference-plate",
        "--monitor",
        "30,20,90",
        "--monitor-every",
        "400",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = gonio(&["calibrate", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (lo, hi) = (
        summary["laser_power_range"][0].as_f64().unwrap(),
        summary["laser_power_range"][1].as_f64().unwrap(),
    );
    assert!(hi - lo > 0.08, "the drift the monitor saw: {lo}…{hi}");
    let splitter = summary["calibration"]["splitter"].as_f64().unwrap();
    assert!((splitter - 0.21).abs() < 0.002, "splitter {splitter}");

    // The file: raw columns and calibrated ones side by side, every scan position once.
    let rows = read_calibrated(&out.join("calibrated.csv"));
    assert_eq!(
        rows.len(),
        common::reachable(&gonio_shared::ScanSpec::belcour_with_patterns()).len()
    );
    let errors: Vec<f64> = rows.iter().map(|(r, f, _)| (f / truth(r) - 1.0).abs()).collect();
    let med = median(errors);
    assert!(med < 0.01, "median |error| {med}");
    // The budget's k = 2 interval covers the truth for most samples (this
    // head is perfect and its plate exactly as certified, so more than the
    // nominal 95 %; coverage-bench checks it on imperfect heads).
    let covered = rows.iter().filter(|(r, f, s)| (f - truth(r)).abs() <= 2.0 * s).count();
    assert!(covered as f64 > 0.95 * rows.len() as f64, "{covered} of {} within 2σ", rows.len());

    // Without the monitor the same data are off by the drift.
    let all = samples::read(&out.join("samples.csv")).unwrap();
    let plate = samples::read(&out.join("reference.csv")).unwrap();
    let cal = Calibration::from_plate(&plate, &[], 0.99, 0.005, None).unwrap();
    let no_monitor: Vec<Row> = all.iter().filter(|r| r.index.is_some()).cloned().collect();
    assert!(
        median_error(&cal, &no_monitor) > 0.015,
        "drift should matter: {}",
        median_error(&cal, &no_monitor)
    );
    assert!(median_error(&cal, &all) < 0.01);

    // The calibrated file is a fitting input: retro-phong recovered.
    let o = gonio(&[
        "fit",
        out.join("calibrated.csv").to_str().unwrap(),
        "--model",
        "retro-phong",
        "--weights",
        "sigma",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let fit: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for (name, want) in ["kd", "n", "k1", "k2"].iter().zip(Material::tape().params) {
        let got = fit["params"][name].as_f64().unwrap();
        assert!((got / want - 1.0).abs() < 0.05, "{name}: {got} vs {want}");
    }
}

/// Rows of calibrated.csv with their `brdf_sr` and `brdf_sigma_sr`.
fn read_calibrated(path: &Path) -> Vec<(Row, f64, f64)> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let (f, s, u) = (col("brdf_sr"), col("brdf_sigma_sr"), col("usable"));
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            assert_eq!(&rec[u], "true");
            let raw: Row = rec.deserialize(Some(&header)).unwrap();
            (raw, rec[f].parse().unwrap(), rec[s].parse().unwrap())
        })
        .collect()
}
