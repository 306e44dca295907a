//! The `alta` section: the models ALTA (the fitting library of Belcour et
//! al. 2014) also has, fitted by its Ceres fitter (`data2brdf --fitter
//! nonlinear_fitter_ceres`) on the same samples as ours, in this run.
//!
//! Shared models: `abc-retro-per-lobe` in the back parametrization (ALTA's
//! retro tutorial: diffuse + ABC(cos θh)·Schlick + ABC(cos θk)·retro-Schlick)
//! and `lafortune` (diffuse + two isotropic Lafortune lobes). Not shared,
//! and so not run: ALTA's Blinn lobes carry an amplitude `ks` that
//! `blinn-retro` (Spieringhs eq. 8–9) has not, and its
//! `nonlinear_function_retroblinn` raises the data's first coordinate (θL
//! here), not a retro cosine; its Beckmann lobe has no Smith shadowing.
//!
//! ALTA is a local fitter: Ceres ends in its start's basin. It runs from its
//! own default start (what a user of ALTA gets) and from 24 random starts in
//! our box, drawn as the scipy peer of `misfit` draws them; its best is the
//! reference. Per case: `rmse_ratio` = ours / ALTA's best (bar ≤ 1 + 1e-9);
//! `time_ratio` = our whole global fit / ALTA's 25 fits (bar < 1), ALTA's
//! time being each `data2brdf` run's wall time less that of a run of zero
//! iterations (reading the text file, setting the problem up, writing the
//! result), and the median of one fit; `l2_agreement`, the largest relative
//! difference between the L2 ALTA prints (its RMSE, six digits) and ours of
//! its parameters (read from its function file, ten digits): both sides
//! evaluate one function on the same geometries.
//!
//! ALTA is not installed here: `ALTA_DIR` names a build of it (holding
//! `build/softs/data2brdf` and `build/plugins`) whose diffuse term is
//! fitted (`-DFIT_DIFFUSE`; without it ALTA holds kd at the data's minimum,
//! a narrower model, which the section refuses). `ALTA_COMMIT` names its
//! commit where `ALTA_DIR` is no git checkout. Without `ALTA_DIR` the
//! section says so and runs nothing.

use gonio_analysis::fit::{self, FitSpec, Problem};
use gonio_analysis::formats::alta as alta_file;
use gonio_brdf::{ModelId, Param};
use rand::SeedableRng;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::cases::materials;
use crate::{peer_starts, rmse, PEER_STARTS};

/// A model of ours as ALTA's plugins compose it.
struct Shared {
    model: ModelId,
    param: Param,
    /// `data2brdf --func`.
    func: &'static str,
    /// ALTA's parameter vector (the order of its `found parameters`) as ours.
    to_ours: fn(&[f64]) -> Vec<f64>,
    /// ALTA's `.brdf` text of our parameters, a start it loads.
    start_file: fn(&[f64]) -> String,
}

const HEADER: &str = "#ALTA FUNC HEADER\n#ALTA HEADER END\n\n";

/// ALTA: `[kd, a_r, b_r, c_r, R_r, a_b, b_b, c_b, R_b]`, its diffuse term
/// `kd` without 1/π; ours: `kd, r0_b, ab, bb, cb, r0_r, ar, br, cr`.
fn abc_to_ours(a: &[f64]) -> Vec<f64> {
    vec![PI * a[0], a[8], a[5], a[6], a[7], a[4], a[1], a[2], a[3]]
}

fn abc_start(p: &[f64]) -> String {
    let lobe = |param: &str, a: f64, b: f64, c: f64| format!("#FUNC nonlinear_function_abc\n#PARAM {param}\na {a:e}\nb {b:e}\nc {c:e}\n\n");
    let mut s = String::from(HEADER);
    let _ = write!(s, "#FUNC nonlinear_function_diffuse\nkd {:e}\n\n", p[0] / PI);
    s += &lobe("COS_TH", p[6], p[7], p[8]);
    let _ = write!(s, "#FUNC nonlinear_fresnel_schlick\nR {:e}\n\n", p[5]);
    s += &lobe("COS_TK", p[2], p[3], p[4]);
    let _ = write!(s, "#FUNC nonlinear_fresnel_retro_schlick\nR {:e}\n\n", p[1]);
    s
}

/// ALTA: `[kd, Cxy, Cz, N, Cxy, Cz, N]`; ours the same with kd·π.
fn lafortune_to_ours(a: &[f64]) -> Vec<f64> {
    std::iter::once(PI * a[0]).chain(a[1..].iter().copied()).collect()
}

fn lafortune_start(p: &[f64]) -> String {
    let mut s = String::from(HEADER);
    let _ = write!(
        s,
        "#FUNC nonlinear_function_diffuse\nkd {:e}\n\n#FUNC nonlinear_function_lafortune\n#NB_LOBES 2\n",
        p[0] / PI
    );
    for lobe in p[1..].chunks(3) {
        let _ = write!(s, "Cxy {:e}\nCz {:e}\nN {:e}\n\n", lobe[0], lobe[1], lobe[2]);
    }
    s
}

const SHARED: [Shared; 2] = [
    Shared {
        model: ModelId::AbcRetroPerLobe,
        param: Param::Back,
        func: "[nonlinear_function_diffuse, nonlinear_function_abc --fresnel nonlinear_fresnel_schlick, \
               nonlinear_function_abc --param COS_TK --fresnel nonlinear_fresnel_retroschlick]",
        to_ours: abc_to_ours,
        start_file: abc_start,
    },
    Shared {
        model: ModelId::Lafortune,
        param: Param::View,
        func: "[nonlinear_function_diffuse, nonlinear_function_lafortune --lobes 2]",
        to_ours: lafortune_to_ours,
        start_file: lafortune_start,
    },
];

/// A build of ALTA and a scratch folder for its files.
pub struct Alta {
    /// The build's checkout (its `documents/data` holds measured tapes).
    pub dir: PathBuf,
    pub work: PathBuf,
}

/// What one `data2brdf` run gave.
struct Run {
    /// Ours, mapped from ALTA's `found parameters`.
    params: Vec<f64>,
    /// The L2 ALTA prints (six digits): sqrt(mean squared error).
    l2: f64,
    seconds: f64,
}

impl Alta {
    pub fn locate() -> Result<Alta, String> {
        let dir = PathBuf::from(std::env::var("ALTA_DIR").map_err(|_| "ALTA_DIR is not set: it names a build of ALTA".to_string())?);
        if !dir.join("build/softs/data2brdf").is_file() {
            return Err(format!("{} holds no build/softs/data2brdf", dir.display()));
        }
        let work = std::env::temp_dir().join(format!("fit-bench-alta-{}", std::process::id()));
        std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
        Ok(Alta { dir, work })
    }

    pub fn commit(&self) -> String {
        let git = Command::new("git").arg("-C").arg(&self.dir).args(["rev-parse", "HEAD"]).output();
        match git {
            Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout).trim().to_string(),
            _ => std::env::var("ALTA_COMMIT").unwrap_or_else(|_| "unknown (set ALTA_COMMIT)".into()),
        }
    }

    /// `data2brdf` on `data` from `start` (ALTA's own default where `None`),
    /// `iterations` capping Ceres's.
    /// `data2brdf --input data --output WORK/fit.brdf ARGS`: what it
    /// printed, its wall time, and whether it exited with success.
    pub fn run(&self, data: &Path, args: &[&str]) -> Result<(String, f64, bool), String> {
        let out = self.work.join("fit.brdf");
        let _ = std::fs::remove_file(&out);
        let t0 = Instant::now();
        let o = Command::new(self.dir.join("build/softs/data2brdf"))
            .env("ALTA_PLUGIN_PATH", self.dir.join("build/plugins"))
            .arg("--input")
            .arg(data)
            .arg("--output")
            .arg(&out)
            .args(args)
            .stderr(Stdio::null())
            .output()
            .map_err(|e| format!("data2brdf: {e}"))?;
        Ok((
            String::from_utf8_lossy(&o.stdout).into_owned(),
            t0.elapsed().as_secs_f64(),
            o.status.success(),
        ))
    }

    fn fit(&self, shared: &Shared, data: &Path, start: Option<&[f64]>, iterations: Option<u32>) -> Result<Run, String> {
        let mut args = vec!["--fitter", "nonlinear_fitter_ceres", "--func", shared.func];
        let file = self.work.join("start.brdf");
        if let Some(p) = start {
            std::fs::write(&file, (shared.start_file)(p)).map_err(|e| e.to_string())?;
            args.extend(["--bootstrap", file.to_str().ok_or("a scratch path that is not UTF-8")?]);
        }
        let n = iterations.map(|n| n.to_string());
        if let Some(n) = &n {
            args.extend(["--ceres-max-num-iterations", n]);
        }
        let (text, seconds, success) = self.run(data, &args)?;
        if !success {
            return Err("data2brdf failed".into());
        }
        let out = self.work.join("fit.brdf");
        let line = |key: &str| {
            text.lines()
                .find_map(|l| l.split_once(key).map(|(_, rest)| rest.trim().to_string()))
        };
        // The function file has ten digits where the `found parameters` line
        // has six; its values come in that line's order.
        let brdf = std::fs::read_to_string(&out).map_err(|e| format!("data2brdf wrote no function ({e})"))?;
        let found: Vec<f64> = brdf
            .split_once("#ALTA HEADER END")
            .map_or("", |(_, body)| body)
            .lines()
            .filter(|l| !l.starts_with('#'))
            .filter_map(|l| l.split_whitespace().nth(1))
            .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
            .collect();
        let fitted = line("found parameters:").map_or(0, |v| v.split(',').count());
        if fitted + 1 == shared.model.param_names().len() {
            return Err("ALTA held kd at the data's minimum: build it with -DFIT_DIFFUSE".into());
        }
        if found.len() != shared.model.param_names().len() {
            return Err(format!(
                "ALTA's function has {} parameters, {} has {}",
                found.len(),
                shared.model.name(),
                shared.model.param_names().len()
            ));
        }
        let l2 = line("L2   distance to data =").and_then(|v| v.parse().ok()).unwrap_or(f64::NAN);
        Ok(Run {
            params: (shared.to_ours)(&found),
            l2,
            seconds,
        })
    }
}

impl Drop for Alta {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.work);
    }
}

/// The Ceres version of the headers ALTA was built against.
fn ceres_version() -> String {
    let text = ["/usr/include/ceres/version.h", "/usr/local/include/ceres/version.h"]
        .iter()
        .find_map(|p| std::fs::read_to_string(p).ok())
        .unwrap_or_default();
    let part = |name: &str| {
        text.lines().find_map(|l| {
            l.strip_prefix(&format!("#define CERES_VERSION_{name} "))
                .map(|v| v.trim().to_string())
        })
    };
    match (part("MAJOR"), part("MINOR"), part("REVISION")) {
        (Some(a), Some(b), Some(c)) => format!("{a}.{b}.{c}"),
        _ => "unknown (no ceres/version.h)".into(),
    }
}

/// ALTA's RMSE evaluated by us, and its relative difference from ALTA's own.
fn ours_of(problem: &Problem, run: &Run) -> (f64, f64) {
    let r = rmse(problem, &run.params);
    (r, ((r - run.l2) / run.l2).abs())
}

/// The section: the first `limit` cases whose `SAMPLES/MATERIAL/MODEL`
/// holds `filter`.
pub fn alta(limit: usize, filter: &str) -> Value {
    let alta = match Alta::locate() {
        Ok(a) => a,
        Err(why) => {
            eprintln!("fit-bench alta: skipped: {why}");
            return json!({ "skipped": why });
        }
    };
    let mut rng = rand::rngs::StdRng::seed_from_u64(25);
    let mut rows = Vec::new();
    let (mut worst_rmse, mut worst_time, mut worst_l2) = (0.0f64, 0.0f64, 0.0f64);
    for m in materials() {
        for shared in &SHARED {
            if rows.len() >= limit || m.model == Some(shared.model) {
                continue;
            }
            let spec = FitSpec {
                param: shared.param,
                ..FitSpec::new(shared.model)
            };
            let problem = fit::problem(&m.data, &spec).expect("alta problem");
            // Drawn for every case, so a case's starts do not depend on the filter.
            let starts = peer_starts(&mut rng, &problem);
            let label = format!("{}/{}/{}", m.samples, m.material, shared.model.name());
            if !label.contains(filter) {
                continue;
            }
            let file = alta.work.join("data.dat");
            std::fs::write(&file, alta_file::write(&m.data)).expect("data file written");
            let run = |start: Option<&[f64]>, iterations| alta.fit(shared, &file, start, iterations);
            let load = match run(None, Some(0)) {
                Ok(r) => r.seconds,
                Err(why) => {
                    eprintln!("fit-bench alta: {why}");
                    return json!({ "error": why });
                }
            };
            let ours = fit::fit(&m.data, &spec).expect("our fit");
            let ours_x: Vec<f64> = problem.free.iter().map(|&i| ours.material.params[i]).collect();
            let r_ours = rmse(&problem, &ours_x);

            let default = run(None, None);
            let (mut best, mut best_params, mut failed, mut l2_diff) = (f64::INFINITY, Vec::new(), 0, 0.0f64);
            let mut times = Vec::new();
            let mut default_rmse = f64::NAN;
            for (k, r) in std::iter::once(default)
                .chain(starts.iter().map(|s| run(Some(s), None)))
                .enumerate()
            {
                match r {
                    Ok(r) => {
                        times.push((r.seconds - load).max(0.0));
                        let (rm, diff) = ours_of(&problem, &r);
                        if k == 0 {
                            default_rmse = rm;
                        }
                        if rm.is_finite() {
                            l2_diff = l2_diff.max(diff);
                            if rm < best {
                                (best, best_params) = (rm, r.params);
                            }
                        } else {
                            failed += 1;
                        }
                    }
                    Err(why) => {
                        eprintln!("fit-bench alta {label}: {why}");
                        failed += 1;
                    }
                }
            }
            let seconds: f64 = times.iter().sum();
            times.sort_by(f64::total_cmp);
            let median = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
            // No ALTA run to compare with is a miss, not a ratio of 0.
            let rmse_ratio = if best.is_finite() { r_ours / best } else { f64::INFINITY };
            let time_ratio = ours.seconds / seconds;
            worst_rmse = worst_rmse.max(rmse_ratio);
            worst_time = worst_time.max(time_ratio);
            worst_l2 = worst_l2.max(l2_diff);
            eprintln!(
                "alta {label:<40} rmse ratio {rmse_ratio:.9} (ALTA's default start {:.4}×)  time ratio {time_ratio:.3} ({:.2} s vs {seconds:.2} s)",
                default_rmse / r_ours,
                ours.seconds
            );
            rows.push(json!({
                "samples": m.samples, "material": m.material, "model": shared.model.name(),
                "rmse": r_ours, "alta_rmse": best, "alta_default_start_rmse": default_rmse, "rmse_ratio": rmse_ratio,
                "seconds": ours.seconds, "alta_seconds": seconds, "alta_median_fit_seconds": median, "alta_load_seconds": load, "time_ratio": time_ratio,
                "l2_agreement": l2_diff, "alta_failed_runs": failed, "params": ours.material.params, "alta_params": best_params,
            }));
        }
    }
    let bars_met = !rows.is_empty() && worst_rmse <= 1.0 + 1e-9 && worst_time < 1.0;
    json!({
        "alta_commit": alta.commit(), "ceres": ceres_version(), "starts": PEER_STARTS + 1, "cases": rows,
        "max_rmse_ratio": worst_rmse, "max_time_ratio": worst_time, "max_l2_disagreement": worst_l2,
        "bars_met": bars_met,
    })
}
