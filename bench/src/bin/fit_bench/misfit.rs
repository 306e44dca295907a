//! The `misfit` section: ours from no start (the global search) against
//! `least_squares` from 24 random starts in the same box, on every case.

use gonio_analysis::fit::{self, FitSpec};
use rand::SeedableRng;
use serde_json::{json, Value};

use crate::cases::cases;
use crate::{job, peer_params, peer_starts, rmse, scipy};

/// The first `limit` cases whose label holds `filter`; returns the table
/// and the worst RMSE and time ratios.
pub fn misfit(limit: usize, filter: &str) -> (Value, f64, f64) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(24);
    let mut rows = Vec::new();
    let (mut worst_rmse, mut worst_time) = (0.0f64, 0.0f64);
    for case in cases() {
        if rows.len() >= limit {
            break;
        }
        let (data, model) = (&*case.data, case.model);
        let spec = FitSpec::new(model);
        let problem = fit::problem(data, &spec).expect("misfit problem");
        // Drawn for every case, so a case's starts do not depend on the filter.
        let starts = peer_starts(&mut rng, &problem);
        if !case.label().contains(filter) {
            continue;
        }
        let ours = fit::fit(data, &spec).expect("misfit fit");
        let peer = scipy(&job(model, &problem, json!({ "starts": starts }), json!({})));
        let peer_params = peer_params(&peer);
        let ours_x: Vec<f64> = problem.free.iter().map(|&i| ours.material.params[i]).collect();
        let (r_ours, r_peer) = (rmse(&problem, &ours_x), rmse(&problem, &peer_params));
        let peer_seconds = peer["seconds"].as_f64().unwrap_or(f64::NAN);
        let (rmse_ratio, time_ratio) = (r_ours / r_peer, ours.seconds / peer_seconds);
        worst_rmse = worst_rmse.max(rmse_ratio);
        worst_time = worst_time.max(time_ratio);
        eprintln!(
            "misfit {:<40} rmse ratio {rmse_ratio:.9}  time ratio {time_ratio:.3} ({:.2} s vs {:.2} s)  at bound {:?}",
            case.label(),
            ours.seconds,
            peer_seconds,
            ours.at_bound
        );
        rows.push(json!({
            "samples": case.samples, "material": case.material, "model": model.name(), "rmse": r_ours, "peer_rmse": r_peer,
            "rmse_ratio": rmse_ratio, "seconds": ours.seconds, "peer_seconds": peer_seconds, "time_ratio": time_ratio,
            "peer_failed_starts": peer["failed_starts"], "peer_params": peer_params,
            "at_bound": ours.at_bound, "params": ours.material.params,
        }));
    }
    (Value::Array(rows), worst_rmse, worst_time)
}
