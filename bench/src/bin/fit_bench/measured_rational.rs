//! The `rational` section's measured tapes: the rational function through
//! ±0.5 sr⁻¹ segments of tapes measured by the CEA head of Belcour et al.
//! 2014, as ALTA publishes them (`ALTA_DIR/documents/data/retro-*.dat`,
//! f_r·cosθo, views out to 90°), and of `tests/data/tape-frcos.dat`, which
//! mimics them; ours beside ALTA's `rational_fitter_quadprog` on the same
//! rows (our reader's: grazing rows dropped) in the file's own quantity,
//! as the paper fitted them.
//!
//! ALTA's own walk raises its counts one term at a time from one, each a
//! programme from scratch: at these sizes that is hours (its programme of
//! 600 terms a side alone takes 44 s here). ALTA is given our search
//! instead, galloping then bisecting over counts, one `data2brdf` run per
//! count (`--min-np n --np n`): its time is the sum of those runs, which
//! favours ALTA. Ours: as `gonio fit FILE --model rational --segments
//! abs:0.5 --max-degree 14` fits it (the warped light-view plane raced
//! with ALTA's view plane, the cosine factor), one fit, its coefficients
//! and its time.
//!
//! Densified (§6.A.b): ours on a 2° grid interpolated between the samples
//! (`fit::densify`), with how many measured segments the function still
//! holds; reported, with no bar. ALTA is not run on the paper's densified
//! files (`retro-*-dense.dat`, 68 579 rows and more): its programme is
//! dense, 2 rows × 2n doubles a sample, 1.5 GB at 700 terms a side.

use gonio_analysis::fit::Dataset;
use gonio_analysis::formats::{self, alta as alta_file};
use gonio_analysis::moments::Parametrization;
use gonio_analysis::rational::{self, search, RationalSpec, SegmentSource};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::alta::Alta;
use crate::rational::printed_linf;

/// The segments' half-width, sr⁻¹ (Belcour et al. 2014's ±0.5).
const HALF_WIDTH: f64 = 0.5;

/// ALTA's searches stop here: 700 terms a side, beyond the 600 its walk
/// needed on the yellow tape.
const ALTA_MOST_TERMS: usize = 700;

/// The degree ours may reach: 1 360 coefficients, beyond ALTA's 1 200.
const OUR_DEGREE: usize = RationalSpec::HIGHEST_DEGREE;

/// The degree our densified fits may reach: 572 coefficients. A densified
/// grid is piecewise linear between the samples, kinked at each, and on a
/// narrow lobe no degree may hold it: on the mimic tape none up to 512
/// coefficients did, the next counts taking minutes each (on the yellow
/// tape 146 held).
const DENSIFIED_DEGREE: usize = 10;

/// The grid step of our densified fits, degrees (the paper's files: 1.07°;
/// at 1° a tape is 71 000 points, four times 2°'s, for the same lobes).
const DENSIFY_STEP_DEG: f64 = 2.0;

/// A measured tape: its name and its file.
struct Tape {
    name: String,
    file: PathBuf,
}

fn tapes(alta: &Alta) -> Vec<Tape> {
    let ours = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/tape-frcos.dat");
    let mut out = vec![Tape {
        name: "tape-frcos (ours, mimics a measured tape)".into(),
        file: ours,
    }];
    let published = alta.dir.join("documents/data");
    for name in ["retro-3M-jaune", "retro-gray-tape"] {
        let file = published.join(format!("{name}.dat"));
        if file.is_file() {
            out.push(Tape {
                name: format!("{name} (ALTA's, measured by CEA)"),
                file,
            });
        } else {
            eprintln!("fit-bench rational: {} is not in ALTA_DIR", file.display());
        }
    }
    out
}

/// ALTA at `terms` a side on `file`: whether it held every segment (it
/// says it got a fit, and its printed L∞ is the half-width to the six
/// digits it prints), and its wall time.
fn alta_at(alta: &Alta, file: &Path, terms: usize) -> Result<(bool, f64), String> {
    let n = terms.to_string();
    let args = [
        "--fitter",
        "rational_fitter_quadprog",
        "--func",
        "rational_function_legendre",
        "--dt",
        &HALF_WIDTH.to_string(),
        "--min-np",
        &n,
        "--np",
        &n,
        "--min-nq",
        &n,
        "--nq",
        &n,
    ];
    let (text, seconds, _) = alta.run(file, &args)?;
    let held = text.contains("got a fit using") && printed_linf(&text) <= HALF_WIDTH * (1.0 + 1e-5);
    Ok((held, seconds))
}

/// ALTA's search on `file`: coefficients, seconds, counts tried.
fn alta_search(alta: &Alta, file: &Path) -> Value {
    let mut seconds = 0.0;
    let mut tried = Vec::new();
    let found = search::fewest(1, 1, ALTA_MOST_TERMS, |terms| {
        let (held, s) = alta_at(alta, file, terms)?;
        eprintln!(
            "rational ALTA {}: {terms} terms a side {} in {s:.1} s",
            file.display(),
            if held { "held" } else { "failed" }
        );
        seconds += s;
        tried.push(terms);
        Ok::<_, String>(if held { Ok(terms) } else { Err(()) })
    });
    match found {
        Ok(terms) => json!({"coefficients": terms.ok().map(|t| 2 * t), "seconds": seconds, "terms_tried": tried}),
        Err(e) => json!({"error": e, "seconds": seconds}),
    }
}

/// Ours on `data`, as the command line fits it: with the cosine factor,
/// unless a row is grazing, where the factor is zero (the gray tape stores
/// `f_r` out to θo = 90°), as `--no-cosine` fits it.
fn ours(data: &Dataset, densify: Option<f64>) -> Value {
    let grazing = data.observations.iter().any(rational::grazing);
    let spec = RationalSpec {
        parametrization: Parametrization::LightView,
        segments: SegmentSource::Absolute(HALF_WIDTH),
        max_degree: if densify.is_some() { DENSIFIED_DEGREE } else { OUR_DEGREE },
        cosine: !grazing,
        densify,
    };
    let t0 = Instant::now();
    let fit = rational::fit(data, &spec);
    let seconds = t0.elapsed().as_secs_f64();
    let name = fit
        .as_ref()
        .map_or("light-view or view-projected", |f| f.function.coordinates.name());
    eprintln!(
        "rational ours{}: {name}: {} in {seconds:.1} s",
        if densify.is_some() { " densified" } else { "" },
        fit.as_ref()
            .map_or_else(|e| format!("{e:#}"), |f| format!("{} coefficients", f.function.coefficients()))
    );
    match fit {
        Ok(f) => json!({
            "coordinates": name, "cosine": spec.cosine, "coefficients": f.function.coefficients(), "degree": f.function.degree,
            "seconds": seconds, "worst_violation": f.worst_violation, "linf": f.linf,
            "precision": if f.single_precision { "single" } else { "double" },
            "samples": f.samples, "densified": f.densified,
        }),
        Err(e) => json!({"coordinates": name, "seconds": seconds, "error": format!("{e:#}")}),
    }
}

/// Its coefficients and time, if it held every segment.
fn held(run: &Value) -> Option<(u64, f64)> {
    run["worst_violation"].as_f64().filter(|w| *w <= 1e-9)?;
    Some((run["coefficients"].as_u64()?, run["seconds"].as_f64()?))
}

/// The measured tapes' rows of the section, and whether each met the bar
/// (as many coefficients as ALTA or fewer, in no more time).
pub fn measured(alta: &Alta, filter: &str) -> (Vec<Value>, bool) {
    let mut rows = Vec::new();
    let mut met = true;
    for tape in tapes(alta).into_iter().filter(|t| t.name.contains(filter)) {
        let data = match formats::load(&tape.file, None) {
            Ok(d) => d,
            Err(e) => {
                met = false;
                rows.push(json!({"material": tape.name, "error": format!("{e:#}")}));
                continue;
            }
        };
        // ALTA reads the rows ours fits, in the file's own quantity.
        let file = alta.work.join("measured.dat");
        if let Err(e) = std::fs::write(&file, alta_file::write(&data)) {
            met = false;
            rows.push(json!({"material": tape.name, "error": e.to_string()}));
            continue;
        }
        let peer = alta_search(alta, &file);
        let run = ours(&data, None);
        let alta_ran = peer.get("error").is_none();
        let (ratio_n, ratio_t) = match (held(&run), peer["coefficients"].as_u64(), peer["seconds"].as_f64()) {
            (Some((n, t)), Some(k), Some(s)) => (n as f64 / k as f64, t / s),
            // ALTA held at no count up to its most: ours holding is ahead.
            (Some(_), None, Some(_)) if alta_ran => (0.0, 0.0),
            _ => (f64::INFINITY, f64::INFINITY),
        };
        // Neither holding at any count it may try: no bar to meet, said so.
        let neither = alta_ran
            && peer["coefficients"].is_null()
            && run
                .get("error")
                .is_some_and(|e| e.as_str().is_some_and(|e| e.starts_with("no rational function")));
        let bar_met = neither || (ratio_n <= 1.0 && ratio_t <= 1.0);
        met &= bar_met;
        let densified = ours(&data, Some(DENSIFY_STEP_DEG));
        rows.push(json!({
            "material": tape.name, "file": tape.file, "samples": data.observations.len(),
            "units": data.units, "half_width_sr": HALF_WIDTH, "dropped": data.warnings,
            "ours": run, "alta": peer,
            "coefficient_ratio": ratio_n, "time_ratio": ratio_t, "bar_met": bar_met, "neither_held": neither,
            "densified": {"step_deg": DENSIFY_STEP_DEG, "max_degree": DENSIFIED_DEGREE, "ours": densified},
        }));
    }
    (rows, met)
}
