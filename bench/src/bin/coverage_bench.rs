//! `coverage-bench`: is the uncertainty budget honest? Scans of the
//! simulated head, each with its own imperfections (stage zeros, backlash,
//! gain ranges, stray light, a plate off its certificate) drawn from the
//! head's stated uncertainties, calibrated by `gonio calibrate`'s code; the
//! share of samples whose truth (the virtual material at the reported
//! geometry, as the detector's field sees it) lies inside the k = 2
//! interval, per incidence angle and near / far from the retro peak. Then
//! retro-phong fitted to each scan with 1/σ weights, and R_A (ASTM E810 set,
//! ε = 0) and R_L (EN 1436) as `gonio coefficients --fit` gives them from
//! the fit and its data's support, against the material's own: their
//! coverage, and linear propagation of the fit's covariance against Monte
//! Carlo (on the extrapolated values, which the fit carries). Then
//! `coefficients_by_family`: scans of the glass-bead material (none of the
//! models) and of the tape on imperfect heads, with EN 1436's incidence,
//! every model fitted, and R_A on the ASTM E810 grid and R_L as `gonio
//! coefficients --fit fits/*.json` gives them (the data where they hold the
//! geometry, adequate models within the data's spacing, nothing beyond
//! unless asked), against the material's own through the same apertures:
//! their k = 2 coverage per family (R_A at measured incidences, R_A at
//! entrance angles not measured, R_L measured, every extrapolation given
//! unasked, and what `--extrapolate` adds), each with its count, the
//! largest model spread at R_A(0.2°, −4°) over its expanded uncertainty,
//! and the samples within 5° of the laser per
//! incidence. One JSON object on stdout.
//!
//! `cargo run --release -p gonio-bench --bin coverage-bench [-- SCANS [NONMODEL_SCANS [RL_SCANS]]]`
//! (default 100, 20 and 500).

use gonio::cli::demo::demo_scan;
use gonio::cli::fit_args::FitOptions;
use gonio::cli::fitting::compare;
use gonio::cli::output::OutputArgs;
use gonio_analysis::calibration;
use gonio_analysis::calibration::directory::{self, calibrate, Calibrated};
use gonio_analysis::coefficients::{self, Cie, Fitted, Provenance, Request, Source, Support};
use gonio_analysis::fit::comparison::Row;
use gonio_analysis::fit::{self, FitSpec, Weighting};
use gonio_analysis::uncertainty::{HeadUncertainty, K_COVERAGE};
use gonio_brdf::frame::angle_between;
use gonio_brdf::{Directions, Material, ModelId, Param, Specimen};
use gonio_firmware::config::REFERENCE;
use gonio_shared::ScanSpec;
use gonio_sim::{seen_brdf, Imperfections, SimConfig, PLATE_RHO_U};
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
    let nonmodel_scans: u64 = std::env::args().nth(2).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let rl_scans: u64 = std::env::args().nth(3).map(|s| s.parse()).transpose()?.unwrap_or(500);
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    let mut nonmodel = json!({
        "glass_beads": provenance_coverage(&rt, Specimen::default(), nonmodel_scans)?,
        "tape": provenance_coverage(&rt, Specimen::Model(Material::tape()), nonmodel_scans)?,
    });
    for (name, material) in [("glass_beads", Specimen::default()), ("tape", Specimen::Model(Material::tape()))] {
        nonmodel[name]["families"]["rl_measured_alone"] = rl_coverage(&rt, material, rl_scans)?;
    }
    let truth = Material::tape();
    let detector_sr = REFERENCE.optics.detector_sr as f64;
    let reqs = coefficients::report_requests();
    let truth_src = Source::model(truth.clone());
    let mut all = Tally::default();
    let mut groups: BTreeMap<(i32, bool), Tally> = BTreeMap::new();
    let (mut coef, mut coef_near) = (Tally::default(), Tally::default());
    let mut mc_ratio: Vec<f64> = Vec::new();
    let mut per_scan = Vec::new();
    let mut not_given = 0;
    for seed in 1..=scans {
        let (_dir, imperfections, c) = imperfect_scan(&rt, seed, &Specimen::Model(truth.clone()), &ScanSpec::belcour_with_patterns())?;
        let (mut scan, mut scan_near) = (Tally::default(), Tally::default());
        for r in c.rows.iter().filter(|r| r.usable) {
            let g = &r.raw;
            // What the head's detector sees there: the material averaged over its field.
            let d = Directions::from_degrees(g.theta_i_deg as f64, g.theta_o_deg as f64, g.dphi_deg as f64);
            let f = seen_brdf(&Specimen::Model(truth.clone()), detector_sr, &d);
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
        // As `gonio coefficients --fit fit.json` takes it: the fit and its
        // data's support (measured values from the data, the rest from the fit).
        let src = Source::measured(vec![Fitted::from(&f)], Support::of(&data)?)?;
        let mut scan_coef = Tally::default();
        for (k, (got, want)) in coefficients::compute(&src, &reqs)?
            .iter()
            .zip(coefficients::compute(&truth_src, &reqs)?)
            .enumerate()
        {
            let e = &got.estimate;
            // A value the data cannot support is not given (EN 1436's
            // 88.76° on this grid): `coefficients_by_family` measures it.
            if e.value.is_nan() {
                not_given += 1;
                continue;
            }
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
            "geometries_per_scan": reqs.len(), "not_given": not_given},
        "monte_carlo_vs_linear": {"cases": mc_ratio.len(), "max_relative_difference": worst_mc},
        "per_scan": per_scan,
        "coefficients_by_family": nonmodel,
        "bars": {"coverage_k2": [0.93, 0.98], "monte_carlo_vs_linear": 0.10,
                 "coefficients_by_family": {"every_family_coverage_k2": [0.93, 0.98],
                                            "model_spread_over_u_max": 1.0, "retro_zone_samples_min": 300}},
    });
    println!("{v}");
    Ok(())
}

/// `coefficients_by_family` for one material: `scans` imperfect heads each
/// scanning the plate and the default grid with its patterns and what EN
/// 1436 needs (`--for en1436`: θi 88.76°, a 1.05° ring; ASTM E810's −4°,
/// 40° and 45° left to the models), calibrated, every model fitted with 1/σ
/// weights, and the coefficients from the fits and the data
/// (`Source::measured`) against the material's own, counted per family:
/// R_A at measured incidences, R_A at entrance angles not measured, R_L
/// measured, every extrapolation given unasked; and what `--extrapolate`
/// adds, apart.
fn provenance_coverage(rt: &tokio::runtime::Runtime, material: Specimen, scans: u64) -> anyhow::Result<serde_json::Value> {
    let mut reqs: Vec<Request> = coefficients::Set::AstmE810
        .requests()
        .into_iter()
        .filter(|r| r.geometry.epsilon_deg == 0.0)
        .collect();
    reqs.extend(coefficients::Set::En1436.requests());
    let truth = coefficients::compute(&Source::Truth(material.clone()), &reqs)?;
    let spread_at = Cie::coplanar(0.2, -4.0, 0.0);
    let mut spec = ScanSpec::belcour_with_patterns();
    coefficients::scan::measure_for(&mut spec, &[coefficients::Set::En1436])?;
    let mut tallies: BTreeMap<&'static str, Tally> = BTreeMap::new();
    let mut spread_over_u: f64 = 0.0;
    let mut retro_zone_min = usize::MAX;
    let mut per_scan = Vec::new();
    let options = FitOptions {
        weights: Weighting::Sigma,
        json: true,
        ..FitOptions::default()
    };
    for seed in 1..=scans {
        let (_dir, _, c) = imperfect_scan(rt, seed, &material, &spec)?;
        let data = calibration::dataset(&c.rows);
        // Below 85°: at EN 1436's 88.76° half of every ring lies beyond
        // the horizon.
        for ti in data.incidence_angles_deg().into_iter().filter(|t| *t < 85.0) {
            let near = data
                .observations
                .iter()
                .filter(|o| (o.theta_i.to_degrees() - ti).abs() < 0.05)
                .filter(|o| angle_between(o.directions().l, o.directions().v).to_degrees() <= 5.0)
                .count();
            retro_zone_min = retro_zone_min.min(near);
        }
        // Models only: the rational function carries no value beyond the
        // data, and within them the data carry every value themselves.
        let outcomes = compare(&options.select(&c.summary.file)?, &options, None)?.rows;
        let fits: Vec<Fitted> = outcomes.iter().map(|o| o.fit.fitted()).collect();
        let source = Source::measured(fits, Support::of(&data)?)?;
        let got = coefficients::compute(&source, &reqs)?;
        let asked = coefficients::compute(&source.clone().extrapolating(true), &reqs)?;
        let mut scan: BTreeMap<&'static str, Tally> = BTreeMap::new();
        for ((g, x), t) in got.iter().zip(&asked).zip(&truth) {
            let e = &g.estimate;
            let p = e.basis.as_ref().map_or(Provenance::NotMeasured, |b| b.provenance);
            let inside = |e: &coefficients::Estimate| (e.value - t.estimate.value).abs() <= K_COVERAGE * e.u;
            let ra = g.request.kind == coefficients::Kind::Ra;
            let mut families = Vec::new();
            match p {
                Provenance::Measured | Provenance::Interpolated if ra => families.push("ra_measured_incidences"),
                Provenance::Measured | Provenance::Interpolated => families.push("rl_measured"),
                Provenance::Extrapolated => {
                    families.push("extrapolated_unasked");
                    if ra && !support_holds(&data, g.sample_angles_deg[0]) {
                        families.push("ra_unmeasured_entrance");
                    }
                }
                Provenance::NotMeasured => {
                    scan.entry("not_given").or_default().add(false);
                    tallies.entry("not_given").or_default().add(false);
                    tallies.entry("extrapolated_on_request").or_default().add(inside(&x.estimate));
                }
            }
            for f in families {
                tallies.entry(f).or_default().add(inside(e));
                scan.entry(f).or_default().add(inside(e));
            }
            if g.request.kind == coefficients::Kind::Ra && g.request.geometry == spread_at && e.u > 0.0 {
                let (lo, hi) = e
                    .models
                    .iter()
                    .fold((e.value, e.value), |(lo, hi), m| (lo.min(m.value), hi.max(m.value)));
                spread_over_u = spread_over_u.max((hi - lo) / (K_COVERAGE * e.u));
            }
        }
        let best = source_best(&outcomes);
        eprintln!(
            "{} scan {seed}: best {best}; coverage {}",
            match &material {
                Specimen::GlassBeads(_) => "glass beads",
                Specimen::Model(_) => "tape",
            },
            scan.iter()
                .map(|(k, t)| format!("{k} {:.3} ({})", t.share(), t.all))
                .collect::<Vec<_>>()
                .join(", ")
        );
        per_scan.push(json!({"seed": seed, "best": best,
            "coverage_k2": scan.iter().map(|(k, t)| (k.to_string(), json!({"values": t.all, "coverage_k2": t.share()}))).collect::<serde_json::Map<_, _>>()}));
    }
    Ok(json!({
        "scans": scans,
        "families": tallies.iter().map(|(k, t)| match *k {
            "not_given" => (k.to_string(), json!({"values": t.all})),
            _ => (k.to_string(), json!({"values": t.all, "coverage_k2": t.share()})),
        }).collect::<serde_json::Map<_, _>>(),
        "model_spread_over_u": spread_over_u,
        "retro_zone_samples": retro_zone_min,
        "adequate_p": gonio_analysis::fit::goodness::ADEQUATE_P,
        "per_scan": per_scan,
    }))
}

/// The plate and the default grid with its patterns scanned by an imperfect
/// head drawn from `seed`, calibrated by `gonio calibrate`'s code; the
/// directory holds the files while it lives.
fn imperfect_scan(
    rt: &tokio::runtime::Runtime,
    seed: u64,
    material: &Specimen,
    spec: &ScanSpec,
) -> anyhow::Result<(tempfile::TempDir, Imperfections, Calibrated)> {
    let dir = tempfile::tempdir()?;
    let u = HeadUncertainty::default();
    let imperfections = gonio_sim::Imperfections::drawn(seed, u.zero_deg, u.backlash_deg, u.gain_rel, u.stray_a, PLATE_RHO_U);
    let sim = SimConfig {
        seed,
        imperfections: Box::new(imperfections.clone()),
        material: material.clone(),
        sample_mm: Some(gonio_scan_dir::record::SAMPLE_MM),
        ..SimConfig::default()
    };
    rt.block_on(demo_scan(
        sim,
        spec,
        dir.path(),
        &OutputArgs { force: false, json: true },
        &Default::default(),
    ))?;
    let c = calibrate(&directory::Request::for_scan(
        dir.path().to_path_buf(),
        gonio_sim::PLATE_RHO,
        gonio_sim::PLATE_RHO_U,
    ))?;
    Ok((dir, imperfections, c))
}

/// R_L measured, a value a scan: one scan's family holds too few values to
/// tell 0.93 from 0.98 (binomial σ 0.034 at 40). So `scans` more imperfect
/// heads scan the plate and only what EN 1436 needs (θi 88.76°, its rings
/// with the 1.05° one, the retro point), and R_L from the data alone
/// (`gonio coefficients --data`) is held against the material's own.
fn rl_coverage(rt: &tokio::runtime::Runtime, material: Specimen, scans: u64) -> anyhow::Result<serde_json::Value> {
    let mut spec = ScanSpec {
        theta_i_deg: heapless::Vec::new(),
        theta_o: gonio_shared::AngleRange::new(88.76, 88.76, 1.0),
        dphi: gonio_shared::AngleRange::new(0.0, 0.0, 1.0),
        ..ScanSpec::belcour_with_patterns()
    };
    coefficients::scan::measure_for(&mut spec, &[coefficients::Set::En1436])?;
    let reqs = coefficients::Set::En1436.requests();
    let truth = coefficients::compute(&Source::Truth(material.clone()), &reqs)?[0].estimate.value;
    let mut tally = Tally::default();
    for seed in 1..=scans {
        // Heads other than the families' (seeds from 1001).
        let (_dir, _, c) = imperfect_scan(rt, 1000 + seed, &material, &spec)?;
        let got = coefficients::compute(&Source::data(&calibration::dataset(&c.rows))?, &reqs)?;
        let e = &got[0].estimate;
        anyhow::ensure!(
            e.basis.as_ref().is_some_and(|b| b.provenance == Provenance::Measured),
            "R_L not measured on seed {seed}: {:?}",
            e.basis
        );
        tally.add((e.value - truth).abs() <= K_COVERAGE * e.u);
    }
    Ok(json!({"values": tally.all, "coverage_k2": tally.share()}))
}

/// Whether the data hold the incidence `theta_i_deg`.
fn support_holds(data: &fit::Dataset, theta_i_deg: f64) -> bool {
    data.incidence_angles_deg().iter().any(|t| (t - theta_i_deg).abs() < 0.1)
}

/// The name of the fit with the lowest AIC.
fn source_best(outcomes: &[Row]) -> &'static str {
    outcomes
        .iter()
        .min_by(|a, b| a.fit.criteria().aic.total_cmp(&b.fit.criteria().aic))
        .map_or("none", |o| o.fit.name())
}
