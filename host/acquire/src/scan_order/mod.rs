//! A scan's visit order, planned on the host and streamed to the head in
//! chunks (`gonio/visits`), what an order costs, and how far it is from the
//! fastest possible.
//!
//! Within each incidence angle, the unreachable points come first (they cost
//! no motion) and the reachable ones follow along the shortest path of
//! *move times* under the axis limits that local search finds ([`tour`]),
//! starting from where the previous incidence ended. The search is
//! deterministic, so the duration estimate and a resumed scan follow the same
//! order; an incidence with more points than [`SEARCH_CAPACITY`] falls back to
//! the serpentine of `ScanSpec::index_at_order`.
//!
//! Why here and not on the head: `docs/decisions/001-host-plans-the-visit-order.md`.

mod bound;
mod duration;
mod tour;

pub use bound::{lower_bound, MoveBound, BOUND_CAPACITY};
pub use duration::{dwell_s, scan_time, sweep_time, time_left_s, ScanTime};

use gonio_firmware::config::HeadConfig;
use gonio_firmware::kinematics;
use gonio_firmware::motion::{move_time, target_steps};
use gonio_shared::ScanSpec;

/// Points of one incidence angle planned by search.
pub const SEARCH_CAPACITY: usize = 4096;

/// Stage targets (microsteps) of the points of incidence `block` in canonical
/// order, `None` where a point is unreachable.
pub fn stage_targets(cfg: &HeadConfig, spec: &ScanSpec, block: u32) -> Vec<Option<[i32; 3]>> {
    let per_block = spec.len() / spec.theta_i_deg.len().max(1) as u32;
    (block * per_block..(block + 1) * per_block)
        .map(|i| {
            let g = spec.point(i)?;
            kinematics::inverse(cfg, &g).ok().map(|axes| target_steps(cfg, &axes))
        })
        .collect()
}

/// Duration (s) of the move between two stage positions (microsteps).
pub fn move_s(cfg: &HeadConfig, from: [i32; 3], to: [i32; 3]) -> f64 {
    move_time(cfg, [0, 1, 2].map(|i| to[i] - from[i]))
}

/// The visit order of a whole scan (canonical indices), from stage position
/// `from` (microsteps). A sweep scan's positions follow
/// `ScanSpec::index_at_order` (its rows each starting where the previous
/// one ended).
pub fn visit_order(cfg: &HeadConfig, spec: &ScanSpec, from: [i32; 3]) -> impl Iterator<Item = u32> {
    let n = spec.len();
    if spec.sweep.is_some() {
        return (0..n).filter_map(|o| spec.index_at_order(o)).collect::<Vec<_>>().into_iter();
    }
    let blocks = spec.theta_i_deg.len() as u32;
    let per_block = n / blocks.max(1);
    let mut order = Vec::with_capacity(n as usize);
    let mut at = from;
    for block in 0..blocks {
        let base = block * per_block;
        if per_block as usize > SEARCH_CAPACITY {
            order.extend((base..base + per_block).filter_map(|o| spec.index_at_order(o)));
            continue;
        }
        let targets = stage_targets(cfg, spec, block);
        order.extend((0..per_block).filter(|&k| targets[k as usize].is_none()).map(|k| base + k));
        let reachable: Vec<u32> = (0..per_block).filter(|&k| targets[k as usize].is_some()).collect();
        let node = |k: usize| {
            if k == 0 {
                at
            } else {
                targets[reachable[k - 1] as usize].unwrap_or(at)
            }
        };
        let path = tour::shortest_path(reachable.len(), |a, b| move_s(cfg, node(a), node(b)));
        if let Some(&last) = path.last() {
            at = node(last);
        }
        order.extend(path.into_iter().map(|k| base + reachable[k - 1]));
    }
    order.into_iter()
}
