//! `cargo run --release -p tests --bin scan-bench`: how close a scan comes
//! to the physical limit, as one JSON object on stdout (a table on stderr).
//!
//! - `plan_over_lower_bound`: head time of the planned Belcour grid (moves
//!   under the reference axis limits, the chip's planning, 50 ms settle and
//!   100 ms integration per point, from the park position) over the lower
//!   bound of any stop-and-go visit of its points from any start
//!   (`scan_order::lower_bound`), beside the old nearest-neighbour plan's
//!   figure (`old_plan_s`, replayed here).

use gonio_firmware::config::{HeadConfig, REFERENCE};
use gonio_firmware::motion::PARK;
use gonio_host::scan_order::{lower_bound, move_s, scan_time, stage_targets, visit_order};
use gonio_shared::ScanSpec;
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
    println!("{out}");
}
