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
//! abs:0.5 --max-degree 14` fits it (the light-view plane, the cosine
//! factor), one fit, its coefficients and its time.
//!
//! Densified (§6.A.b): ours on a 2° grid interpolated between the samples
//! (`fit::densify`), with how many measured segments the function still
//! holds; reported, with no bar. ALTA is not run on the paper's densified
//! files (`retro-*-dense.dat`, 68 579 rows and more): its programme is
//! dense, 2 rows × 2n doubles a sample, 1.5 GB at 700 terms a side.

use gonio_analysis::fit::Dataset;
use gonio_analysis::formats::{self, alta as alta_file};
use gonio_analysis::moments::Parametrization;
use gonio_analysis::rational::{self, RationalSpec, SegmentSource};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::alta::Alta;

/// The segments' half-width, sr⁻¹ (Belcour et al. 2014's ±0.5).
const HALF_WIDTH: f64 = 0.5;

/// ALTA's searches stop here: 700 terms a side, beyond the 600 its walk
/// needed on the yellow tape.
const ALTA_MOST_TERMS: usize = 700;

/// The degree ours may reach: 1 360 coefficients, beyond ALTA's 1 200.
const OUR_DEGREE: usize = RationalSpec::HIGHEST_DEGREE;

/// The grid step of our densified fits, degrees (the paper's files: 1.07°;
/// at 1° a tape is 71 000 points, four times 2°'s, for the same lobes).
const DENSIFY_STEP_DEG: f64 = 2.0;

/// A measured tape: its name and its file.
struct Tape {
    name: String,
    file: PathBuf,
}

fn tapes(alta: &Alta) -> Vec<Tape> {
    let ours = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/tape-frcos.dat");
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

/// ALTA at `terms` a side on `file`: whether it held every segment, and
/// its wall time.
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
    Ok((text.contains("got a fit using"), seconds))
}

/// The fewest terms a side at which `holds` holds, by galloping then
/// bisection up to `most`, with every count tried; `None` if none did.
fn fewest(most: usize, mut holds: impl FnMut(usize) -> Result<bool, String>) -> Result<(Option<usize>, Vec<usize>), String> {
    let mut tried = Vec::new();
    let (mut lo, mut n) = (1, 1);
    let mut hi = loop {
        tried.push(n);
        if holds(n)? {
            break n;
        }
        if n == most {
            return Ok((None, tried));
        }
        lo = n + 1;
        n = (2 * n).min(most);
    };
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        tried.push(mid);
        if holds(mid)? {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    Ok((Some(hi), tried))
}

/// ALTA's search on `file`: coefficients, seconds, counts tried.
fn alta_search(alta: &Alta, file: &Path) -> Value {
    let mut seconds = 0.0;
    let found = fewest(ALTA_MOST_TERMS, |terms| {
        let (held, s) = alta_at(alta, file, terms)?;
        eprintln!(
            "rational ALTA {}: {terms} terms a side {} in {s:.1} s",
            file.display(),
            if held { "held" } else { "failed" }
        );
        seconds += s;
        Ok(held)
    });
    match found {
        Ok((terms, tried)) => json!({"coefficients": terms.map(|t| 2 * t), "seconds": seconds, "terms_tried": tried}),
        Err(e) => json!({"error": e, "seconds": seconds}),
    }
}

/// Ours on `data`, as the command line fits it.
fn ours(data: &Dataset, densify: Option<f64>) -> Value {
    let spec = RationalSpec {
        parametrization: Parametrization::LightView,
        segments: SegmentSource::Absolute(HALF_WIDTH),
        max_degree: OUR_DEGREE,
        cosine: true,
        densify,
    };
    let t0 = Instant::now();
    let fit = rational::fit(data, &spec);
    let seconds = t0.elapsed().as_secs_f64();
    let name = "light-view × cosθi·cosθo";
    eprintln!(
        "rational ours{}: {name}: {} in {seconds:.1} s",
        if densify.is_some() { " densified" } else { "" },
        fit.as_ref()
            .map_or_else(|e| format!("{e:#}"), |f| format!("{} coefficients", f.function.coefficients()))
    );
    match fit {
        Ok(f) => json!({
            "function": name, "coefficients": f.function.coefficients(), "degree": f.function.degree,
            "seconds": seconds, "worst_violation": f.worst_violation, "linf": f.linf,
            "precision": if f.single_precision { "single" } else { "double" },
            "samples": f.samples, "densified": f.densified,
        }),
        Err(e) => json!({"function": name, "seconds": seconds, "error": format!("{e:#}")}),
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
        let (ratio_n, ratio_t) = match (held(&run), peer["coefficients"].as_u64(), peer["seconds"].as_f64()) {
            (Some((n, t)), Some(k), Some(s)) => (n as f64 / k as f64, t / s),
            // ALTA held at no count up to its most: ours holding is ahead.
            (Some(_), None, Some(_)) if peer.get("error").is_none() => (0.0, 0.0),
            _ => (f64::INFINITY, f64::INFINITY),
        };
        let bar_met = ratio_n <= 1.0 && ratio_t <= 1.0;
        met &= bar_met;
        let densified = ours(&data, Some(DENSIFY_STEP_DEG));
        rows.push(json!({
            "material": tape.name, "file": tape.file, "samples": data.observations.len(),
            "units": data.units, "half_width_sr": HALF_WIDTH, "dropped": data.warnings,
            "ours": run, "alta": peer,
            "coefficient_ratio": ratio_n, "time_ratio": ratio_t, "bar_met": bar_met,
            "densified": {"step_deg": DENSIFY_STEP_DEG, "ours": densified},
        }));
    }
    (rows, met)
}
