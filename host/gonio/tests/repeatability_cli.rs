//! Repeated scans of one simulated sample, each with its own reference-plate
//! scan and noise: `gonio repeatability` finds the repeats' scatter where
//! the budget predicts it, and says so as text, JSON, CSV and a picture.

mod common;
use common::{gonio, text};

/// `n` scans of the simulated sample with `grid`, seeds 1 to `n`, each
/// with its own plate scan, calibrated: their directories.
fn repeats(dir: &std::path::Path, n: u64, grid: &[&str]) -> Vec<String> {
    (1..=n)
        .map(|seed| {
            let o = dir.join(format!("run{seed}")).to_str().unwrap().to_string();
            let seed = seed.to_string();
            let mut args = vec!["scan", "--sim", "--reference-plate", "--out", &o, "--seed", &seed, "--json"];
            args.extend_from_slice(grid);
            let s = gonio(&args);
            assert!(s.status.success(), "{}", text(&s));
            let c = gonio(&["calibrate", &o, "--json"]);
            assert!(c.status.success(), "{}", text(&c));
            o
        })
        .collect()
}

#[test]
fn repeats_scatter_as_the_budget_predicts() {
    let dir = tempfile::tempdir().unwrap();
    let scans = repeats(
        dir.path(),
        4,
        &["--theta-i", "30", "--theta-o", "0:60:6", "--dphi", "0:180:45", "--no-patterns"],
    );
    let (plots, csv) = (dir.path().join("plots"), dir.path().join("rep.csv"));
    let mut args: Vec<&str> = vec!["repeatability"];
    args.extend(scans.iter().map(String::as_str));
    args.extend(["--plot", plots.to_str().unwrap(), "--csv", csv.to_str().unwrap(), "--json"]);
    let o = gonio(&args);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let geometries = v["geometries"].as_array().unwrap();
    // 11 view angles × 5 azimuths, the normal once: 51 geometries, less the
    // two in the splitter's blind zone (θo = 24° and 36° at Δφ = 0), each
    // measured four times.
    assert_eq!(geometries.len(), 49, "{v}");
    assert!(geometries.iter().all(|g| g["n"] == 4));
    let ratio = v["median_ratio"].as_f64().unwrap();
    assert!((0.5..2.0).contains(&ratio), "s / predicted σ: {ratio}");
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 50);
    let svg = std::fs::read_to_string(plots.join("repeatability.svg")).unwrap();
    assert!(svg.contains("predicted σ of a repeat (sr⁻¹)") && svg.contains("θi = 30°") && svg.contains("s = σ"));
    let t = gonio(&["repeatability", &scans[0], &scans[1]]);
    assert!(t.status.success() && text(&t).contains("geometries in common"), "{}", text(&t));
    let one = gonio(&["repeatability", &scans[0]]);
    assert_eq!(one.status.code(), Some(2), "one scan is a usage error: {}", text(&one));
}

/// The bar, on five repeats of one incidence with its rings about
/// the retro peak: s over the budget's σ has a median within 0.8–1.25 over
/// the whole grid, and within 0.8–1.5 at the peaks, where the splitter's
/// factor (set by the plate's retro points) dominates the budget.
#[test]
fn five_repeats_meet_the_budget_at_the_peaks_too() {
    let dir = tempfile::tempdir().unwrap();
    let scans = repeats(dir.path(), 5, &["--theta-i", "30"]);
    let mut args: Vec<&str> = vec!["repeatability", "--json"];
    args.extend(scans.iter().map(String::as_str));
    let o = gonio(&args);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (median, peaks) = (v["median_ratio"].as_f64().unwrap(), v["peak_median_ratio"].as_f64().unwrap());
    assert!((0.8..=1.25).contains(&median), "s / predicted σ: median {median}");
    assert!((0.8..=1.5).contains(&peaks), "s / predicted σ at the peaks: {peaks}");
}
