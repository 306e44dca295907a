//! A lower bound on the head time of any stop-and-go visit of a scan's
//! points from any starting position, the yardstick of the planner
//! (`scan-bench`'s `plan_over_lower_bound`) and of a finished scan's head
//! time.
//!
//! The dwell (settle and integration) is the same for every order. For the
//! moves, two bounds, the larger of which is taken:
//! - *shortest entry*: every reachable point but the first is entered by a
//!   move from another point, so the moves take at least the sum over the
//!   points of the shortest move into each, less the largest such move (the
//!   first point's entry, from wherever the stages were, may cost nothing);
//! - *two neighbours*: a move costs the same both ways, and on the path every
//!   point but the first and the last touches two moves between points, those
//!   two touch one. Summing each point's two cheapest moves counts every
//!   move of the path at most twice once the first and the last point's
//!   second cheapest are taken out; as they are not known, the two largest
//!   second cheapest are. Half that sum bounds the moves.
//!
//! The chip's planning of the moves (tens of microseconds a block) is left
//! out: the bound is what the stages and the detector need. It takes a time
//! quadratic in the number of points, so scans larger than
//! [`BOUND_CAPACITY`] go without one.

use super::duration::ScanTime;
use super::{move_s, stage_targets};
use gonio_firmware::config::HeadConfig;
use gonio_shared::ScanSpec;

/// Reachable points up to which the bound is computed (a few seconds).
pub const BOUND_CAPACITY: usize = 12_288;

/// The two cheapest moves seen so far touching one point.
#[derive(Clone, Copy)]
struct Cheapest([f64; 2]);

impl Cheapest {
    fn offer(&mut self, t: f64) {
        if t < self.0[0] {
            self.0 = [t, self.0[0]];
        } else if t < self.0[1] {
            self.0[1] = t;
        }
    }
}

/// The two bounds on the moves (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MoveBound {
    pub shortest_entry_s: f64,
    pub two_neighbours_s: f64,
}

/// The bound for `spec`, with `settle_s` and `integration_s` of dwell per
/// measured point, and the two bounds on its moves; `None` for a scan of
/// more than [`BOUND_CAPACITY`] reachable points.
pub fn lower_bound(cfg: &HeadConfig, spec: &ScanSpec, settle_s: f64, integration_s: f64) -> Option<(ScanTime, MoveBound)> {
    let mut points: Vec<[i32; 3]> = Vec::new();
    for block in 0..spec.theta_i_deg.len() as u32 {
        points.extend(stage_targets(cfg, spec, block).into_iter().flatten());
        if points.len() > BOUND_CAPACITY {
            return None;
        }
    }
    let n = points.len();
    let mut cheapest = vec![Cheapest([f64::INFINITY; 2]); n];
    for (a, &p) in points.iter().enumerate() {
        for b in a + 1..n {
            let t = move_s(cfg, p, points[b]);
            cheapest[a].offer(t);
            cheapest[b].offer(t);
        }
    }
    let firsts: Vec<f64> = cheapest.iter().map(|c| c.0[0]).collect();
    // With one point there is no move between points; with two, one, which
    // the entry bound gives exactly (their second cheapest is infinite).
    let entry = if n < 2 {
        0.0
    } else {
        firsts.iter().sum::<f64>() - firsts.iter().copied().fold(0.0, f64::max)
    };
    let two = if n < 3 {
        entry
    } else {
        let mut seconds: Vec<f64> = cheapest.iter().map(|c| c.0[1]).collect();
        seconds.sort_by(|x, y| y.total_cmp(x));
        (firsts.iter().sum::<f64>() + seconds.iter().sum::<f64>() - seconds[0] - seconds[1]) / 2.0
    };
    let moves = MoveBound {
        shortest_entry_s: entry,
        two_neighbours_s: two,
    };
    let time = ScanTime {
        moves_s: entry.max(two),
        planning_s: 0.0,
        settle_s: settle_s * n as f64,
        integration_s: integration_s * n as f64,
        measured: n as u32,
        skipped: spec.len() - n as u32,
    };
    Some((time, moves))
}
