//! `cargo run --release -p tests --bin scan-bench`: how close a scan comes
//! to the physical limit, as one JSON object on stdout (a table on stderr).
//!
//! - `plan_over_lower_bound`: head time of the planned Belcour grid (moves
//!   under the reference axis limits, the chip's planning, 50 ms settle and
//!   100 ms integration per point, from the park position) over the lower
//!   bound of any stop-and-go visit of its points from any start
//!   (`scan_order::lower_bound`), beside the old nearest-neighbour plan's
//!   figure (`old_plan_s`, replayed here).
//! - `sweep`: arcs of θo in the plane of incidence measured while moving, on
//!   the simulated head driven directly, at two speeds, each beside the same
//!   arc measured stop-and-go on its 3° grid (head times on the simulated
//!   head's clock, both from the park position): samples, head times, their
//!   ratio (`arc_time_ratio`), and `tag_error_deg_max`, the largest
//!   difference between a sample's tag and the true mean geometry of its
//!   conversions. A swept sample integrates fewer periods than a grid point
//!   (`periods_per_sample`, `grid_periods_per_point`), so it is noisier. A
//!   refused arc is listed with its reason and counted in `refused_arcs`.
//!   The sweep scan of a whole grid's coverage
//!   (`sweep_time_ratio` of issue #20) and the fits are not built yet.

use gonio_firmware::config::{HeadConfig, REFERENCE};
use gonio_firmware::motion::PARK;
use gonio_host::scan_order::{lower_bound, move_s, scan_time, stage_targets, visit_order};
use gonio_shared::{AngleRange, DetectionSettings, Geometry, ScanSpec, SweepRequest};
use gonio_sim::SimConfig;
use gonio_tests::sweeping::{tag_error_deg_max, SimHead};
use serde_json::{json, Value};
use std::time::Instant;

const SETTLE_S: f64 = 0.05;
const INTEGRATION_S: f64 = 0.1;

/// The plan of the previous release: nearest neighbour by move time within
/// each incidence, unreachable points first; kept here as the benchmark's
/// reference.
fn nearest_neighbour_order(cfg: &HeadConfig, spec: &ScanSpec, from: [i32; 3]) -> Vec<u32> {
    let blocks = spec.theta_i_deg.len() as u32;
    let per_block = spec.len() / blocks;
    let mut at = from;
    let mut order = Vec::new();
    for block in 0..blocks {
        let base = block * per_block;
        let targets = stage_targets(cfg, spec, block);
        order.extend((0..per_block).filter(|&k| targets[k as usize].is_none()).map(|k| base + k));
        let mut open: Vec<u32> = (0..per_block).filter(|&k| targets[k as usize].is_some()).collect();
        while !open.is_empty() {
            let time = |k: u32| move_s(cfg, at, targets[k as usize].unwrap_or(at));
            let best = (0..open.len()).fold(0, |b, j| if time(open[j]) < time(open[b]) { j } else { b });
            let k = open.remove(best);
            at = targets[k as usize].unwrap_or(at);
            order.push(base + k);
        }
    }
    order
}

/// In-plane arcs of θo (θi, Δφ, θo from, θo to) on the Belcour incidences.
const ARCS: [(f32, f32, f32, f32); 3] = [(30.0, 0.0, 42.0, 87.0), (15.0, 180.0, 0.0, 87.0), (60.0, 180.0, 0.0, 57.0)];
/// Speeds (deg/s of the arm) the arcs are swept at.
const SPEEDS: [f32; 2] = [5.0, 20.0];
/// The grid step the stop-and-go arcs are measured on (the Belcour θo step).
const GRID_STEP_DEG: f32 = 3.0;

/// One arc swept at `speed_dps` and measured stop-and-go on its grid, each
/// on a fresh simulated head from the park position.
fn arc(ti: f32, dp: f32, from: f32, to: f32, speed_dps: f32) -> Value {
    let mut sim = SimHead::homed(&SimConfig::default());
    let req = SweepRequest {
        from: Geometry::new(ti, from, dp),
        to: Geometry::new(ti, to, dp),
        speed_dps,
        periods_per_sample: SweepRequest::PERIODS_MAX,
    };
    let swept = match sim.sweep(req) {
        Ok(s) => s,
        Err(f) => return json!({ "theta_i_deg": ti, "dphi_deg": dp, "theta_o_deg": [from, to], "refused": f.to_string() }),
    };
    let mut still = SimHead::homed(&SimConfig::default());
    let t0 = still.now_s();
    let grid = AngleRange::new(from, to, GRID_STEP_DEG);
    let n = grid.count().unwrap_or(0);
    let measured = (0..n).filter(|&k| still.measure(Geometry::new(ti, grid.at(k), dp)).is_ok()).count();
    let grid_s = still.now_s() - t0;
    json!({
        "theta_i_deg": ti,
        "dphi_deg": dp,
        "theta_o_deg": [from, to],
        "speed_dps": speed_dps,
        "samples": swept.samples.len(),
        "sweep_head_s": swept.head_s,
        "sweep_moving_s": swept.report.duration_s,
        "grid_points": measured,
        "grid_head_s": grid_s,
        "arc_time_ratio": swept.head_s / grid_s,
        "tag_error_deg_max": tag_error_deg_max(&swept),
    })
}

fn main() {
    let cfg = REFERENCE;
    let spec = ScanSpec::belcour();
    let t0 = Instant::now();
    let order: Vec<u32> = visit_order(&cfg, &spec, PARK).collect();
    let planning_wall_s = t0.elapsed().as_secs_f64();
    let plan = scan_time(&cfg, &spec, order.into_iter(), PARK, SETTLE_S, INTEGRATION_S);
    let old = scan_time(
        &cfg,
        &spec,
        nearest_neighbour_order(&cfg, &spec, PARK).into_iter(),
        PARK,
        SETTLE_S,
        INTEGRATION_S,
    );
    let (bound, moves) = lower_bound(&cfg, &spec, SETTLE_S, INTEGRATION_S).expect("3 316 points are bounded");
    let arcs: Vec<Value> = ARCS
        .iter()
        .flat_map(|&(ti, dp, from, to)| SPEEDS.map(|v| arc(ti, dp, from, to, v)))
        .collect();
    let worst = |key: &str| arcs.iter().filter_map(|a| a[key].as_f64()).fold(0.0, f64::max);
    let sweep = json!({
        "periods_per_sample": SweepRequest::PERIODS_MAX,
        "grid_periods_per_point": DetectionSettings::default().periods,
        "refused_arcs": arcs.iter().filter(|a| a.get("refused").is_some()).count(),
        "grid_step_deg": GRID_STEP_DEG,
        "arcs": arcs,
        "tag_error_deg_max": worst("tag_error_deg_max"),
        "arc_time_ratio_max": worst("arc_time_ratio"),
        "fewest_samples_over_grid_points": arcs
            .iter()
            .filter_map(|a| Some(a["samples"].as_f64()? / a["grid_points"].as_f64()?))
            .fold(f64::INFINITY, f64::min),
    });
    let out = serde_json::json!({
        "points": spec.len(),
        "measured_points": plan.measured,
        "lower_bound_s": bound.total_s(),
        "lower_bound_moves_s": bound.moves_s,
        "moves_bound_shortest_entry_s": moves.shortest_entry_s,
        "moves_bound_two_neighbours_s": moves.two_neighbours_s,
        "dwell_s": bound.settle_s + bound.integration_s,
        "plan_s": plan.total_s(),
        "plan_moves_s": plan.moves_s,
        "plan_chip_planning_s": plan.planning_s,
        "old_plan_s": old.total_s(),
        "plan_over_lower_bound": plan.total_s() / bound.total_s(),
        "old_plan_over_lower_bound": old.total_s() / bound.total_s(),
        "host_planning_wall_s": planning_wall_s,
        "sweep": sweep,
    });
    eprintln!(
        "Belcour grid ({} points, {} measured): lower bound {:.0} s (moves {:.0} s), plan {:.0} s (moves {:.0} s), old plan {:.0} s; plan/bound {:.3} (≤ 1.15), old {:.3}; planned in {:.2} s",
        spec.len(),
        plan.measured,
        bound.total_s(),
        bound.moves_s,
        plan.total_s(),
        plan.moves_s,
        old.total_s(),
        plan.total_s() / bound.total_s(),
        old.total_s() / bound.total_s(),
        planning_wall_s
    );
    eprintln!(
        "Arcs swept at {SPEEDS:?} deg/s: tag error ≤ {:.4}° (≤ 0.01), head time ≤ {:.3} of the 3° stop-and-go grid's",
        sweep["tag_error_deg_max"], sweep["arc_time_ratio_max"]
    );
    println!("{out}");
}
