//! `coverage-bench`: is the uncertainty budget honest? Scans of the
//! simulated head, each with its own imperfections (stage zeros, backlash,
//! gain ranges, stray light, a plate off its certificate) drawn from the
//! head's stated uncertainties, calibrated by `gonio calibrate`'s code; the
//! share of samples whose truth (the virtual material at the reported
//! geometry) lies inside the k = 2 interval, per incidence angle and near /
//! far from the retro peak. Then retro-phong fitted to each scan with 1/σ
//! weights, and R_A (ASTM E810 set, ε = 0) and R_L (EN 1436) from the fit
//! against the material's own: their coverage, and linear propagation of
//! the fit's covariance against Monte Carlo. One JSON object on stdout.
//!
//! `cargo run --release -p tests --bin coverage-bench [-- SCANS]` (default 100).

use gonio_brdf::{Directions, Material, ModelId, Param, Specimen};
use gonio_host::calibration;
use gonio_host::cli::calibrate::{self, CalibrateArgs};
use gonio_host::cli::scan::{demo_scan, OutputArgs};
use gonio_host::coefficients::{self, Source};
use gonio_host::fit::{self, FitSpec, Weighting};
use gonio_host::uncertainty::{HeadUncertainty, K_COVERAGE};
use gonio_sim::{SimConfig, PLATE_RHO_U};
use serde_json::json;
use std::collections::BTreeMap;

/// A sample is "near" the retro peak when the arm is within this of the laser (degrees).
const NEAR_RETRO_DEG: f32 = 10.0;

#[derive(Default)]
struct Tally {
    inside: usize,
    all: usize,
}

impl Tally {
    fn add(&mut self, inside: bool) {
        self.all += 1;
        self.inside += inside as usize;
    }
    fn share(&self) -> f64 {
        self.inside as f64 / self.all.max(1) as f64
    }
}

fn main() -> anyhow::Result<()> {
    let scans: u64 = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(100);
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    let truth = Material::tape();
    let reqs = coefficients::report_requests();
    let truth_src = Source::model(truth.clone());
    let mut all = Tally::default();
    let mut groups: BTreeMap<(i32, bool), Tally> = BTreeMap::new();
    let (mut coef, mut coef_near) = (Tally::default(), Tally::default());
    let mut mc_ratio: Vec<f64> = Vec::new();
    let mut per_scan = Vec::new();
    for seed in 1..=scans {
        let dir = tempfile::tempdir()?;
        let imperfections = gonio_host::cli::material::drawn_imperfections(seed, &HeadUncertainty::default(), PLATE_RHO_U);
        let sim = SimConfig {
            seed,
            imperfections: Box::new(imperfections.clone()),
            material: Specimen::Model(truth.clone()),
            ..SimConfig::default()
        };
        rt.block_on(demo_scan(
            sim,
            &gonio_shared::ScanSpec::belcour(),
            dir.path(),
            &OutputArgs { force: false, json: true },
        ))?;
        let c = calibrate::calibrate(&CalibrateArgs::for_scan(dir.path().to_path_buf(), true))?;
        let (mut scan, mut scan_near) = (Tally::default(), Tally::default());
        for r in c.rows.iter().filter(|r| r.usable) {
            let g = &r.raw;
            let f = truth.eval(&Directions::from_degrees(
                g.theta_i_deg as f64,
                g.theta_o_deg as f64,
                g.dphi_deg as f64,
            ));
            let inside = (r.brdf_sr - f).abs() <= K_COVERAGE * r.brdf_sigma_sr;
            all.add(inside);
            scan.add(inside);
            let near = g.psi_deg.abs() < NEAR_RETRO_DEG;
            if near {
                scan_near.add(inside);
            }
            groups.entry((g.target_theta_i_deg.round() as i32, near)).or_default().add(inside);
        }
        // The fit and the coefficients from it.
        let data = calibration::dataset(&c.rows);
        let spec = FitSpec {
            param: Param::View,
            weighting: Weighting::Sigma,
            ..FitSpec::new(ModelId::RetroPhong)
        };
        let f = fit::fit(&data, &spec)?;
        let src = Source::Model {
            material: f.material.clone(),
            covariance: f.covariance.clone(),
        };
        let mut scan_coef = Tally::default();
        for (k, (got, want)) in coefficients::compute(&src, &reqs)?
            .iter()
            .zip(coefficients::compute(&truth_src, &reqs)?)
            .enumerate()
        {
            let e = &got.estimate;
            let inside = (e.value - want.estimate.value).abs() <= K_COVERAGE * e.u;
            coef.add(inside);
            scan_coef.add(inside);
            if got.request.geometry.alpha_deg <= 0.5 {
                coef_near.add(inside);
            }
            // Monte Carlo against linear propagation, on a few of them.
            if seed <= 3 && k % 9 == 0 {
                if let (Some(mc), Some(lin)) = (src.monte_carlo_u(&got.request, 2000, seed), e.u_params) {
                    mc_ratio.push(mc / lin);
                }
            }
        }
        eprintln!(
            "scan {seed}: {} samples, coverage {:.3} (near the retro peak {:.3}); R_A/R_L {:.3}; plate ρ {:.4}, zeros {:?}°",
            scan.all,
            scan.share(),
            scan_near.share(),
            scan_coef.share(),
            imperfections.plate_rho,
            imperfections.zero_offset_deg.map(|x| (x * 1e4).round() / 1e4)
        );
        per_scan.push(
            json!({"seed": seed, "samples": scan.all, "coverage_k2": scan.share(), "near_retro_coverage_k2": scan_near.share(), "coefficients_coverage_k2": scan_coef.share(),
            "fit_params": f.material.params, "imperfections": imperfections}),
        );
    }
    let table: Vec<_> = groups
        .iter()
        .map(|((ti, near), t)| json!({"theta_i_deg": ti, "retro": if *near { "near" } else { "far" }, "samples": t.all, "coverage_k2": t.share()}))
        .collect();
    for ((ti, near), t) in &groups {
        eprintln!(
            "θi {ti:>2}° {:>4}: {:>6} samples, coverage {:.4}",
            if *near { "near" } else { "far" },
            t.all,
            t.share()
        );
    }
    let worst_mc = mc_ratio.iter().map(|r| (r - 1.0).abs()).fold(0.0, f64::max);
    let v = json!({
        "scans": scans,
        "samples": all.all,
        "coverage_k2": all.share(),
        "groups": table,
        "coefficients": {"values": coef.all, "coverage_k2": coef.share(), "alpha_le_0_5_coverage_k2": coef_near.share(),
            "geometries_per_scan": reqs.len()},
        "monte_carlo_vs_linear": {"cases": mc_ratio.len(), "max_relative_difference": worst_mc},
        "per_scan": per_scan,
        "bars": {"coverage_k2": [0.93, 0.98], "monte_carlo_vs_linear": 0.10},
    });
    println!("{v}");
    Ok(())
}
