//! The `rational` section: the rational function through every sample's
//! segment (Belcour et al. 2014 §5.B), ours against ALTA's own rational
//! fitter (`data2brdf --fitter rational_fitter_quadprog`, Pacanowski et
//! al. 2012's programme solved by QuadProg++), on the same samples with the
//! same absolute segments, in this run.
//!
//! Materials outside every model, 7 000 samples: the glass-bead layer and
//! two retro lobes of different widths (`cases.rs`), their 2 % noise drawn
//! once. ALTA fits in the data file's own coordinates (θL, θV·cosΔφ,
//! θV·sinΔφ), with Legendre polynomials (`rational_function_legendre`) and
//! the same times the cosines (`rational_function_cosine`, the paper's
//! "cosine multiplied by a rational function"), raising its numerator's and
//! denominator's counts together one term at a time; the reference is
//! the fewer coefficients of the two, and its time. Ours, in both retro
//! planes. The measured tapes: `measured_rational.rs`. Per case: every segment held (`worst_violation` ≤ 1e-9 of a
//! segment's width; ALTA's L∞ ≤ the half-width), `coefficient_ratio` (ours
//! / the reference's; bar ≤ 1), `time_ratio` (bar ≤ 1).

use gonio_analysis::fit::Dataset;
use gonio_analysis::formats::alta as alta_file;
use gonio_analysis::moments::Parametrization;
use gonio_analysis::rational::{self, RationalSpec, SegmentSource};
use serde_json::{json, Value};
use std::time::Instant;

use crate::alta::Alta;
use crate::cases::materials;

/// The segments' half-width, sr⁻¹ (Belcour et al. 2014's ±0.5).
const HALF_WIDTH: f64 = 0.5;

/// ALTA's functions: the plain Legendre one and the cosine-weighted one.
const ALTA_FUNCTIONS: [&str; 2] = ["rational_function_legendre", "rational_function_cosine"];

/// ALTA's counts are walked up to this many terms in each of numerator and
/// denominator: our degree 8's.
const ALTA_MAX_TERMS: usize = 165;

/// One ALTA run: the counts it held with, its L∞ and its wall time.
struct AltaRational {
    function: &'static str,
    coefficients: Option<usize>,
    linf: f64,
    seconds: f64,
}

fn alta_rational(alta: &Alta, data: &Dataset, function: &'static str) -> Result<AltaRational, String> {
    // No #VS columns: the segments are ALTA's `--dt`, ± the half-width.
    let mut plain = data.clone();
    plain.observations.iter_mut().for_each(|o| o.sigma = None);
    let file = alta.work.join("rational.dat");
    std::fs::write(&file, alta_file::write(&plain)).map_err(|e| e.to_string())?;
    let max = ALTA_MAX_TERMS.to_string();
    let args = [
        "--fitter",
        "rational_fitter_quadprog",
        "--func",
        function,
        "--dt",
        &HALF_WIDTH.to_string(),
        "--min-np",
        "1",
        "--min-nq",
        "1",
        "--np",
        &max,
        "--nq",
        &max,
    ];
    let (text, seconds, success) = alta.run(&file, &args)?;
    // A walk that held at no count ends in failure, having said so.
    if !success && !text.contains("failed") {
        return Err("data2brdf failed".into());
    }
    // `got a fit using np = 14 & nq =  14`.
    let held = text.lines().find_map(|l| {
        let rest = l.split_once("got a fit using np =")?.1;
        let (np, nq) = rest.split_once("& nq =")?;
        Some(np.trim().parse::<usize>().ok()? + nq.trim().parse::<usize>().ok()?)
    });
    let linf = printed_linf(&text);
    Ok(AltaRational {
        function,
        coefficients: held,
        linf,
        seconds,
    })
}

/// The L∞ distance ALTA prints (`Linf distance to data = 0.5`, to six
/// digits), NaN if it printed none.
pub fn printed_linf(text: &str) -> f64 {
    text.lines()
        .find_map(|l| l.split_once("Linf distance to data =").and_then(|(_, v)| v.trim().parse().ok()))
        .unwrap_or(f64::NAN)
}

/// The section, on the materials whose name holds `filter`.
pub fn rational_section(filter: &str) -> Value {
    let alta = match Alta::locate() {
        Ok(a) => a,
        Err(why) => {
            eprintln!("fit-bench rational: skipped: {why}");
            return json!({ "skipped": why });
        }
    };
    let mut rows = Vec::new();
    let mut met = true;
    for m in materials() {
        if m.samples != 7000 || m.model.is_some() || !m.material.contains(filter) {
            continue;
        }
        let peak = m.data.observations.iter().map(|o| o.value).fold(0.0, f64::max);
        let mut peers = Vec::new();
        for function in ALTA_FUNCTIONS {
            match alta_rational(&alta, &m.data, function) {
                Ok(r) => peers.push(r),
                Err(why) => eprintln!("fit-bench rational {}: ALTA {function}: {why}", m.material),
            }
        }
        let reference = peers
            .iter()
            .filter(|p| p.coefficients.is_some() && p.linf <= HALF_WIDTH * (1.0 + 1e-6))
            .min_by_key(|p| p.coefficients);
        let alta_json: Vec<Value> = peers
            .iter()
            .map(|p| json!({"function": p.function, "coefficients": p.coefficients, "linf": p.linf, "seconds": p.seconds}))
            .collect();
        let configs = [Parametrization::LightView, Parametrization::Back]
            .into_iter()
            .flat_map(|plane| [(plane, true), (plane, false)]);
        let reference_count = reference.and_then(|r| r.coefficients);
        // Ours: each plane with and without the cosine factor; the bar is
        // held by the fewest coefficients that hold every segment.
        let mut ours_json = Vec::new();
        let mut best: Option<(usize, f64, String)> = None;
        for (plane, cosine) in configs {
            let spec = RationalSpec {
                parametrization: plane,
                segments: SegmentSource::Absolute(HALF_WIDTH),
                max_degree: RationalSpec::MAX_DEGREE,
                cosine,
                densify: None,
            };
            let t0 = Instant::now();
            let ours = rational::fit(&m.data, &spec);
            let seconds = t0.elapsed().as_secs_f64();
            let name = format!("{}{}", plane.name(), if cosine { " × cosθi·cosθo" } else { "" });
            match &ours {
                Ok(f) if f.worst_violation <= 1e-9 => {
                    let n = f.function.coefficients();
                    if best.as_ref().is_none_or(|(b, t, _)| (n, seconds) < (*b, *t)) {
                        best = Some((n, seconds, name.clone()));
                    }
                }
                _ => {}
            }
            eprintln!(
                "rational {}/{name}: {} in {seconds:.2} s",
                m.material,
                ours.as_ref()
                    .map_or_else(|e| format!("{e:#}"), |f| format!("{} coefficients", f.function.coefficients()))
            );
            ours_json.push(match &ours {
                Ok(f) => json!({
                    "function": name, "coefficients": f.function.coefficients(), "degree": f.function.degree,
                    "seconds": seconds, "worst_violation": f.worst_violation, "linf": f.linf, "rmse": f.metrics.rmse,
                    "attempts": f.attempts,
                }),
                Err(e) => json!({"function": name, "seconds": seconds, "error": format!("{e:#}")}),
            });
        }
        let (coefficient_ratio, time_ratio) = match (&best, reference_count, reference) {
            (Some((n, t, _)), Some(k), Some(r)) => (*n as f64 / k as f64, t / r.seconds),
            // ALTA ran and held at no count: ours holding is ahead.
            (Some(_), _, None) if !peers.is_empty() => (0.0, 0.0),
            // No ALTA run is a miss, not a ratio of 0, as in `alta`.
            _ => (f64::INFINITY, f64::INFINITY),
        };
        let bar_met = coefficient_ratio <= 1.0 && time_ratio <= 1.0;
        met &= bar_met;
        eprintln!(
            "rational {}: ours {:?} against ALTA {:?}: coefficients ×{coefficient_ratio:.3}, time ×{time_ratio:.3}",
            m.material,
            best,
            reference.map(|r| (r.function, r.coefficients, r.seconds))
        );
        rows.push(json!({
            "material": m.material, "samples": m.samples, "peak_sr": peak, "half_width_sr": HALF_WIDTH,
            "ours": ours_json, "best": best.as_ref().map(|b| &b.2),
            "alta": alta_json, "alta_reference": reference.map(|r| r.function),
            "coefficient_ratio": coefficient_ratio, "time_ratio": time_ratio, "bar_met": bar_met,
        }));
    }
    let (measured, measured_met) = crate::measured_rational::measured(&alta, filter);
    met &= measured_met;
    json!({
        "alta_commit": alta.commit(), "cases": rows, "measured": measured, "rational_bar_met": met,
        "bars": "ours: the fewest coefficients that hold every segment (worst_violation <= 1e-9) of both planes with and without the cosine factor; ALTA's: the fewer of its two functions whose L-infinity is within the half-width; coefficient_ratio <= 1 and time_ratio <= 1",
    })
}
