//! `fit-bench`: the fitting engine on synthetic data, against
//! `scipy.optimize.least_squares` (method `trf`) run in the same benchmark.
//!
//! Per model: 7 000 samples at Belcour grid geometries from the reference
//! parameters (`gonio_tests::synthetic::reference`) with 2 % multiplicative
//! noise, f_r units, uniform weights. Figures:
//! - `seconds`, `rmse`, `ncc`: the same fit by both from the same start (the
//!   centre of the search cube mapped through the bounds), same bounds, same
//!   data: the engine's bounded LM against `least_squares(method="trf")`
//!   (`scipy_seconds`, `scipy_rmse`). Both are timed on prepared data: the
//!   geometry terms are computed once before either clock starts (scipy gets
//!   them from the engine). Median of 5 runs each. `speedup_vs_scipy =
//!   scipy_seconds / seconds`, `rmse_ratio_vs_scipy = rmse / scipy_rmse`
//!   (rounded to 12 decimals);
//! - `global_seconds`, `global_rmse`: the engine's whole fit with no starting
//!   point (global search + local fit, seed 1, data preparation included),
//!   `global_rmse_ratio_vs_scipy`;
//! - `global_hits`: of 20 seeds of the global search, how many reach the best
//!   known optimum (the lowest cost any run found, the fit started at the
//!   truth included) within 1e-6 relative;
//! - `model_agreement`: largest relative difference between the numpy model
//!   and the Rust model on the data at the reference parameters.
//!
//! - `misfit`: materials a model does not describe: data from one model (or
//!   from a material outside every model: the glass-bead layer of the
//!   simulated head, two retro lobes of different widths) fitted by the
//!   other retro models, 2 % noise, at 7 000 and 80 000 samples. Ours from
//!   no start (the global search) against `least_squares` from 24 random
//!   starts in the same box (uniform in the search cube), same residuals,
//!   same data, one after the other in this run: per case `rmse_ratio`
//!   (ours / the peer's best; bar ≤ 1 + 1e-9), `time_ratio` (our whole
//!   global fit / the peer's 24 fits; bar ≤ 1/3) and our `at_bound`.
//!
//! - `widen`: every misfit case fitted again from default boxes cut at
//!   their open edges to about a tenth (`widen.rs`): per case `rmse_ratio`
//!   (cut / full box; bar ≤ 1 + 1e-9 where the boxes the fit ended in
//!   hold the full-box optimum), what widened and what did not hold it;
//! - `gof`: per model the share of 200 σ-weighted fits to its own data
//!   whose reduced χ² lies in its 99 % interval, and of all of them
//!   (`gof.rs`; bar ≥ 0.98 pooled, ≥ 0.95 per model).
//! - `alta`: the models ALTA also has, fitted by ALTA's Ceres fitter on the
//!   same samples from its default start and 24 random ones (`alta.rs`;
//!   bars: RMSE ratio ≤ 1 + 1e-9, time ratio < 1); needs `ALTA_DIR`.
//! - `rational`: the rational function through ±0.5 sr⁻¹ segments against
//!   ALTA's rational fitter on the same samples (`rational.rs`; bars:
//!   every segment held, coefficient and time ratios ≤ 1), simulated
//!   materials and measured tapes (`measured_rational.rs`, densified too);
//!   needs `ALTA_DIR`.
//!
//! Ours evaluates the samples and the global search's candidates on every
//! core (`threads`), as the peer's BLAS does.
//!
//! Installs scipy (pinned) with pip if it is missing or another version;
//! prints one JSON object, with the peer's versions and BLAS.

mod alta;
mod cases;
mod gof;
mod measured_rational;
mod misfit;
mod rational;
mod widen;

use gonio_analysis::fit::{self, transform, FitSpec, Problem};
use gonio_brdf::{GeometryTerms, ModelId};
use gonio_tests::synthetic;
use serde_json::{json, Map, Value};
use std::io::Write;
use std::process::{Command, Stdio};
use std::time::Instant;

const SAMPLES: usize = 7000;
/// The peer's versions: the figures depend on them (lafortune's speedup was
/// 3.95 on one machine and 2.05 on another).
const SCIPY: &str = "1.17.1";
const NUMPY: &str = "2.4.6";
const NOISE: f64 = 0.02;
const SEEDS: u64 = 20;
/// Timed runs of each same-start fit, both sides; the median is reported.
/// At least this many…
const REPEATS: usize = 5;
/// …and, for a fit shorter than a millisecond or so, as many as fill this
/// (s) on our side: a median of five sub-millisecond fits moved by 2.5×
/// between two runs (oren-nayar 15.5× and 6.1× scipy).
const TIMED_S: f64 = 0.25;
/// Most timed runs (odd: the median is one of them).
const MOST_REPEATS: usize = 201;

/// Timed runs for a fit that took `once` seconds.
fn repeats_for(once: f64) -> usize {
    let n = ((TIMED_S / once.max(1e-9)).ceil() as usize).clamp(REPEATS, MOST_REPEATS);
    n | 1
}

/// RMSE ratios are rounded to 12 decimals: two fits at the same optimum
/// differ only by the order of summation below that.
fn round12(x: f64) -> f64 {
    (x * 1e12).round() / 1e12
}

fn ensure_scipy() {
    let ok = |c: &mut Command| c.status().map(|s| s.success()).unwrap_or(false);
    let check = format!("import scipy, numpy, sys; sys.exit(scipy.__version__ != '{SCIPY}' or numpy.__version__ != '{NUMPY}')");
    if !ok(Command::new("python3").args(["-c", &check])) {
        eprintln!("fit-bench: installing scipy {SCIPY}, numpy {NUMPY} with pip");
        let (s, n) = (format!("scipy=={SCIPY}"), format!("numpy=={NUMPY}"));
        if !ok(Command::new("python3").args(["-m", "pip", "install", "--quiet", &s, &n])) {
            eprintln!("fit-bench: pip install scipy failed");
            std::process::exit(1);
        }
    }
}

fn geometry_json(p: &Problem) -> Value {
    let col = |f: &dyn Fn(&GeometryTerms) -> f64| Value::from(p.geos.iter().map(f).collect::<Vec<f64>>());
    json!({
        "cos_i": col(&|g| g.cos_i), "cos_o": col(&|g| g.cos_o), "mirror": col(&|g| g.mirror),
        "c": col(&|g| g.retro_cos(p.param)), "nh": col(&|g| g.nh), "vh": col(&|g| g.vh), "vpb": col(&|g| g.vpb),
        "lv_xy": col(&|g| g.lv_xy), "lv_z": col(&|g| g.lv_z), "tan_i": col(&|g| g.tan_i), "tan_o": col(&|g| g.tan_o),
        "oren_nayar": col(&|g| g.oren_nayar), "one_minus_cos_gamma": col(&|g| g.ln_one_minus_cos_gamma.exp()),
        "zhang_g_over_cos_o": col(&|g| g.zhang_g_over_cos_o),
    })
}

/// The peer's job: the problem as the scipy script reads it (`model`,
/// geometry, values, weights, scale, box), with `starts` and `extra`
/// (`check`, `repeats`) added.
fn job(model: ModelId, problem: &Problem, starts: Value, extra: Value) -> Value {
    let bounds = &problem.bounds_all;
    let mut j = json!({
        "model": model.name(), "geometry": geometry_json(problem), "y": problem.y, "weight": problem.weight,
        "scale": problem.scale, "lo": bounds.iter().map(|b| b.lo).collect::<Vec<_>>(),
        "hi": bounds.iter().map(|b| b.hi).collect::<Vec<_>>(),
    });
    for more in [starts, extra] {
        if let (Value::Object(a), Value::Object(b)) = (&mut j, more) {
            a.extend(b);
        }
    }
    j
}

fn scipy(job: &Value) -> Value {
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/python/fit_scipy.py");
    let mut child = Command::new("python3")
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("python3 runs");
    child
        .stdin
        .take()
        .expect("piped")
        .write_all(job.to_string().as_bytes())
        .expect("job written");
    let out = child.wait_with_output().expect("python3 finishes");
    assert!(out.status.success(), "fit_scipy.py failed");
    serde_json::from_slice(&out.stdout).expect("fit_scipy.py prints JSON")
}

/// The parameters the peer answered (NaN where it wrote none).
fn peer_params(answer: &Value) -> Vec<f64> {
    answer["params"]
        .as_array()
        .expect("the peer answers its params")
        .iter()
        .map(|v| v.as_f64().unwrap_or(f64::NAN))
        .collect()
}

/// Random starts of a peer's multi-start fit, as many as scipy's in
/// `misfit` and ALTA's in `alta`: each uniform in the search cube of
/// `problem`'s box.
const PEER_STARTS: usize = 24;

fn peer_starts(rng: &mut impl rand::Rng, problem: &Problem) -> Vec<Vec<f64>> {
    (0..PEER_STARTS)
        .map(|_| {
            problem
                .bounds_all
                .iter()
                .map(|b| transform::from_unit(b, rng.random_range(0.0..1.0)))
                .collect()
        })
        .collect()
}

fn rmse(p: &Problem, x: &[f64]) -> f64 {
    (p.cost(x) / p.y.len() as f64).sqrt()
}

fn main() {
    let mut report = Map::new();
    // `fit-bench misfit|widen [N [FILTER]]`: that table alone (its first N
    // cases, those whose `SAMPLES/MATERIAL/MODEL` holds FILTER);
    // `fit-bench models [MODEL]`: the per-model figures alone;
    // `fit-bench gof`: the χ² trials alone; `fit-bench alta [N [FILTER]]`:
    // ALTA's fits beside ours alone; `fit-bench rational [MATERIAL]`: the
    // rational functions beside ALTA's alone. `widen`, `gof`, `alta` and
    // `rational` need no scipy.
    let mode = std::env::args().nth(1).unwrap_or_default();
    let cases: usize = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(usize::MAX);
    let filter = std::env::args().nth(3).unwrap_or_default();
    match mode.as_str() {
        "widen" => widen_section(&mut report, cases, &filter),
        "gof" => gof_section(&mut report),
        "alta" => {
            report.insert("alta".into(), alta::alta(cases, &filter));
        }
        "rational" => {
            report.insert(
                "rational".into(),
                rational::rational_section(&std::env::args().nth(2).unwrap_or_default()),
            );
        }
        _ => {}
    }
    if matches!(mode.as_str(), "widen" | "gof" | "alta" | "rational") {
        report.insert("threads".into(), fit::threads().into());
        println!("{}", Value::Object(report));
        return;
    }
    ensure_scipy();
    let (misfit_only, models_only) = (mode == "misfit", mode == "models");
    let only_model = std::env::args().nth(2).filter(|_| models_only);
    let mut worst = (f64::INFINITY, 0.0f64, SEEDS);
    for model in ModelId::ALL
        .into_iter()
        .filter(|m| !misfit_only && only_model.as_deref().is_none_or(|name| name == m.name()))
    {
        let truth = synthetic::reference(model);
        let data = synthetic::samples(&truth, SAMPLES, NOISE, 7);
        let spec = FitSpec::new(model);
        let problem = fit::problem(&data, &spec).expect("synthetic data fit");
        let bounds = problem.bounds_all.clone();
        let start: Vec<f64> = bounds.iter().map(|b| transform::from_unit(b, 0.5)).collect();
        let peer_job = |extra: Value| job(model, &problem, json!({ "start": start }), extra);
        let numpy = scipy(&peer_job(json!({ "check": truth.params })));
        let agreement = numpy["values"]
            .as_array()
            .expect("values")
            .iter()
            .zip(problem.predict(&truth.params))
            .map(|(a, b)| (a.as_f64().unwrap_or(f64::NAN) - b).abs() / b.abs().max(1e-12))
            .fold(0.0, f64::max);

        let full = fit::fit(&data, &spec).expect("fit");
        let t0 = Instant::now();
        let mut local = fit::solve(&problem, Some(&start), 1);
        let repeats = repeats_for(t0.elapsed().as_secs_f64());
        let mut times = Vec::new();
        for _ in 0..repeats {
            let t0 = Instant::now();
            local = fit::solve(&problem, Some(&start), 1);
            times.push(t0.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let local_seconds = times[repeats / 2];
        let sp = scipy(&peer_job(json!({ "repeats": repeats })));
        let sp_params = peer_params(&sp);
        let sp_seconds = sp["seconds"].as_f64().unwrap_or(f64::NAN);
        let sp_rmse = rmse(&problem, &sp_params);

        let from_truth = fit::fit(
            &data,
            &FitSpec {
                start: Some(truth.params.clone()),
                ..spec.clone()
            },
        )
        .expect("fit from truth");
        let costs: Vec<f64> = (1..=SEEDS)
            .map(|seed| fit::fit(&data, &FitSpec { seed, ..spec.clone() }).expect("seeded fit").cost)
            .collect();
        let best = costs
            .iter()
            .copied()
            .chain([from_truth.cost, full.cost, problem.cost(&local), problem.cost(&sp_params)])
            .fold(f64::INFINITY, f64::min);
        let hits = costs.iter().filter(|&&c| c <= best * (1.0 + 1e-6)).count() as u64;

        let global_rmse = rmse(&problem, &problem.free.iter().map(|&i| full.material.params[i]).collect::<Vec<_>>());
        let local_rmse = rmse(&problem, &local);
        let speedup = sp_seconds / local_seconds;
        let ratio = round12(local_rmse / sp_rmse);
        worst = (worst.0.min(speedup), worst.1.max(ratio), worst.2.min(hits));
        report.insert(
            model.name().into(),
            json!({
                "seconds": local_seconds, "rmse": local_rmse, "scipy_seconds": sp_seconds, "scipy_rmse": sp_rmse,
                "scipy_nfev": sp["nfev"], "speedup_vs_scipy": speedup, "rmse_ratio_vs_scipy": ratio,
                "global_seconds": full.seconds, "global_rmse": global_rmse, "global_rmse_ratio_vs_scipy": round12(global_rmse / sp_rmse),
                "ncc": full.metrics.ncc, "params": full.material.params,
                "global_hits": hits, "global_seeds": SEEDS, "model_agreement": agreement, "repeats": repeats,
            }),
        );
    }
    if models_only {
        println!("{}", Value::Object(report));
        return;
    }
    let (misfit, worst_rmse, worst_time) = misfit::misfit(cases, &filter);
    report.insert("misfit".into(), misfit);
    report.insert("misfit_max_rmse_ratio".into(), worst_rmse.into());
    report.insert("misfit_max_time_ratio".into(), worst_time.into());
    if !misfit_only {
        widen_section(&mut report, cases, &filter);
        gof_section(&mut report);
        report.insert("alta".into(), alta::alta(cases, &filter));
    }
    report.insert("peer".into(), scipy(&json!({"versions": true})));
    report.insert("threads".into(), fit::threads().into());
    report.insert("samples".into(), SAMPLES.into());
    report.insert("noise".into(), NOISE.into());
    report.insert("min_speedup_vs_scipy".into(), worst.0.into());
    report.insert("max_rmse_ratio_vs_scipy".into(), worst.1.into());
    report.insert("min_global_hits".into(), worst.2.into());
    println!("{}", Value::Object(report));
}

fn widen_section(report: &mut Map<String, Value>, cases: usize, filter: &str) {
    let (table, worst, holding) = widen::widen(cases, filter);
    report.insert("widen".into(), table);
    report.insert("widen_max_rmse_excess".into(), worst.into());
    report.insert("widen_cases_holding_full_optimum".into(), holding.into());
    report.insert("widen_bar_met".into(), (holding > 0 && worst <= 1e-9).into());
}

fn gof_section(report: &mut Map<String, Value>) {
    let (table, pooled, worst) = gof::gof();
    report.insert("gof".into(), table);
    report.insert("gof_share_inside".into(), pooled.into());
    report.insert("gof_min_share_inside".into(), worst.into());
    report.insert("gof_bar_met".into(), (pooled >= 0.98 && worst >= 0.95).into());
}
