//! Repeated scans of one sample, geometry by geometry: the mean, the
//! standard deviation of the repeats and the standard deviation the budget
//! predicts for them, side by side (a repeatability figure, ISO 5725-2's
//! s_r, and whether the budget holds it).
//!
//! The prediction keeps the components of `calibrated.csv` that change
//! between two scans of the same sample on the same head, each with its own
//! reference-plate scan: the lock-in noise, the plate's scale `K` and the
//! splitter factor (measured again each time), the laser drift. It leaves
//! out what repeats identically: the plate's certificate, the stage angles
//! (the same zeros after every homing), the gain range, stray light.

mod text;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The share of the geometries, highest means first, that are the peaks.
pub const PEAK_SHARE: f64 = 0.05;

/// The components that differ between repeats (columns of `calibrated.csv`).
pub const REPEATING: [&str; 4] = ["u_noise_sr", "u_scale_sr", "u_splitter_sr", "u_drift_sr"];

/// The columns read from a calibrated.csv row; others are ignored.
#[derive(Debug, Deserialize)]
struct Row {
    target_theta_i_deg: Option<f64>,
    target_theta_o_deg: Option<f64>,
    target_dphi_deg: Option<f64>,
    theta_i_deg: f64,
    theta_o_deg: f64,
    dphi_deg: f64,
    brdf_sr: f64,
    usable: Option<bool>,
    u_noise_sr: f64,
    u_scale_sr: f64,
    u_splitter_sr: f64,
    u_drift_sr: f64,
}

/// One geometry seen in at least two of the scans.
#[derive(Debug, Clone, Serialize)]
pub struct Geometry {
    pub theta_i_deg: f64,
    pub theta_o_deg: f64,
    pub dphi_deg: f64,
    /// Scans that measured it (usable).
    pub n: usize,
    pub mean_sr: f64,
    /// Standard deviation of the repeats (n − 1).
    pub s_sr: f64,
    /// What the budget predicts for it: the repeating components in
    /// quadrature, root mean square over the scans.
    pub u_predicted_sr: f64,
}

impl Geometry {
    /// s over its prediction: about 1 where the budget holds.
    pub fn ratio(&self) -> f64 {
        self.s_sr / self.u_predicted_sr
    }
}

/// The comparison of the scans.
#[derive(Debug, Clone, Serialize)]
pub struct Repeatability {
    pub scans: Vec<PathBuf>,
    pub geometries: Vec<Geometry>,
    /// Median of s / u_predicted over the geometries.
    pub median_ratio: f64,
    /// The same over the peaks: the geometries whose mean lies in the top
    /// [`PEAK_SHARE`] of the means, where the budget's smallest relative
    /// components (the plate's scale, the splitter's factor) dominate.
    pub peak_median_ratio: f64,
    /// √(mean s² / mean u²): the pooled ratio.
    pub pooled_ratio: f64,
    /// Median of s / mean: the relative repeatability.
    pub median_relative_s: f64,
}

/// Where a scan directory keeps its calibrated values; a file is itself.
fn calibrated(path: &Path) -> PathBuf {
    if path.is_dir() {
        path.join("calibrated.csv")
    } else {
        path.to_path_buf()
    }
}

/// The geometry's key: the target angles to 0.01° (reached ones where the
/// file has no target), Δφ in [0°, 360°) and 0 on the normal.
fn key(r: &Row) -> (i64, i64, i64) {
    let k = |x: f64| (x * 100.0).round() as i64;
    let (ti, to, dp) = (
        r.target_theta_i_deg.unwrap_or(r.theta_i_deg),
        r.target_theta_o_deg.unwrap_or(r.theta_o_deg),
        r.target_dphi_deg.unwrap_or(r.dphi_deg),
    );
    let dp = if to.abs() < 0.005 { 0.0 } else { dp.rem_euclid(360.0) };
    (k(ti), k(to), k(dp).rem_euclid(36_000))
}

fn read(path: &Path) -> Result<Vec<Row>> {
    let file = calibrated(path);
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(&file)
        .with_context(|| format!("cannot read {} (run `gonio calibrate` on the scan first)", file.display()))?;
    let rows: Vec<Row> = reader
        .deserialize()
        .collect::<Result<_, _>>()
        .with_context(|| format!("{}: not a calibrated.csv (`gonio calibrate` writes it)", file.display()))?;
    Ok(rows
        .into_iter()
        .filter(|r| r.usable != Some(false) && r.brdf_sr.is_finite())
        .collect())
}

/// Compares the calibrated scans at `paths` (scan directories or their
/// `calibrated.csv`), at least two.
pub fn compare(paths: &[PathBuf]) -> Result<Repeatability> {
    if paths.len() < 2 {
        bail!("repeatability needs two scans or more, {} given", paths.len());
    }
    let mut by_geometry: BTreeMap<(i64, i64, i64), Vec<Row>> = BTreeMap::new();
    for p in paths {
        let mut seen = std::collections::BTreeSet::new();
        for r in read(p)? {
            // A geometry measured twice in one scan (the monitor) counts once.
            if seen.insert(key(&r)) {
                by_geometry.entry(key(&r)).or_default().push(r);
            }
        }
    }
    let geometries: Vec<Geometry> = by_geometry
        .into_iter()
        .filter(|(_, rows)| rows.len() >= 2)
        .map(|((ti, to, dp), rows)| {
            let n = rows.len() as f64;
            let mean = rows.iter().map(|r| r.brdf_sr).sum::<f64>() / n;
            let var = rows.iter().map(|r| (r.brdf_sr - mean).powi(2)).sum::<f64>() / (n - 1.0);
            let u2 = rows
                .iter()
                .map(|r| {
                    [r.u_noise_sr, r.u_scale_sr, r.u_splitter_sr, r.u_drift_sr]
                        .iter()
                        .map(|u| u * u)
                        .sum::<f64>()
                })
                .sum::<f64>()
                / n;
            Geometry {
                theta_i_deg: ti as f64 / 100.0,
                theta_o_deg: to as f64 / 100.0,
                dphi_deg: dp as f64 / 100.0,
                n: rows.len(),
                mean_sr: mean,
                s_sr: var.sqrt(),
                u_predicted_sr: u2.sqrt(),
            }
        })
        .filter(|g| g.u_predicted_sr > 0.0)
        .collect();
    if geometries.is_empty() {
        bail!("the scans share no geometry: repeatability compares repeats of the same grid");
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let mean = |f: &dyn Fn(&Geometry) -> f64| geometries.iter().map(f).sum::<f64>() / geometries.len() as f64;
    let mut by_mean: Vec<&Geometry> = geometries.iter().collect();
    by_mean.sort_by(|a, b| b.mean_sr.total_cmp(&a.mean_sr));
    let peaks = ((geometries.len() as f64 * PEAK_SHARE).ceil() as usize).max(1);
    Ok(Repeatability {
        scans: paths.to_vec(),
        median_ratio: median(geometries.iter().map(Geometry::ratio).collect()),
        peak_median_ratio: median(by_mean[..peaks].iter().map(|g| g.ratio()).collect()),
        pooled_ratio: (mean(&|g| g.s_sr * g.s_sr) / mean(&|g| g.u_predicted_sr * g.u_predicted_sr)).sqrt(),
        median_relative_s: median(geometries.iter().map(|g| g.s_sr / g.mean_sr.abs().max(1e-300)).collect()),
        geometries,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(dir: &Path, name: &str, values: &[(f64, f64)]) -> PathBuf {
        let mut text = String::from(
            "target_theta_i_deg,target_theta_o_deg,target_dphi_deg,theta_i_deg,theta_o_deg,dphi_deg,brdf_sr,usable,u_noise_sr,u_scale_sr,u_splitter_sr,u_drift_sr,u_rho_ref_sr\n",
        );
        for (k, (v, u)) in values.iter().enumerate() {
            text.push_str(&format!("30,{},-180,30.0001,{},180,{v},true,{u},0,0,0,9\n", 10 * k, 10 * k));
        }
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn repeats_meet_their_prediction_geometry_by_geometry() {
        let d = tempfile::tempdir().unwrap();
        let a = file(d.path(), "a.csv", &[(1.0, 0.1), (2.0, 0.1)]);
        let b = file(d.path(), "b.csv", &[(1.2, 0.1), (2.0, 0.1)]);
        let r = compare(&[a, b]).unwrap();
        assert_eq!(r.geometries.len(), 2);
        let g = &r.geometries[0];
        // −180° and 180° are one azimuth; two repeats 0.2 apart: s = 0.2/√2.
        assert_eq!((g.theta_i_deg, g.theta_o_deg, g.dphi_deg, g.n), (30.0, 0.0, 0.0, 2));
        assert!((g.s_sr - 0.2 / 2f64.sqrt()).abs() < 1e-12 && (g.u_predicted_sr - 0.1).abs() < 1e-12);
        assert_eq!(r.geometries[1].dphi_deg, 180.0);
        assert_eq!(r.geometries[1].s_sr, 0.0);
        // The plate's certificate (u_rho_ref = 9) repeats: not in the prediction.
        assert!((r.pooled_ratio - (0.02f64 / 2.0 / 0.01).sqrt()).abs() < 1e-9, "{}", r.pooled_ratio);
    }

    #[test]
    fn one_scan_or_none_in_common_is_refused() {
        let d = tempfile::tempdir().unwrap();
        let a = file(d.path(), "a.csv", &[(1.0, 0.1)]);
        assert!(compare(std::slice::from_ref(&a)).is_err());
        let missing = d.path().join("nothing");
        let e = compare(&[a, missing]).unwrap_err();
        assert!(format!("{e:#}").contains("gonio calibrate"), "{e:#}");
    }
}
