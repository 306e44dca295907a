//! A lower bound on the head time of any stop-and-go visit of a scan's
//! points, the yardstick of the planner (`scan-bench`'s
//! `plan_over_lower_bound`).
//!
//! The dwell (settle and integration) is the same for every order. For the
//! moves, two bounds, the larger of which is returned:
//! - *shortest entry*: every reachable point is entered exactly once, by one
//!   move from the start or from another point, so the moves take at least
//!   the sum over the points of the shortest move into each;
//! - *two neighbours*: a move costs the same both ways, and on the path every
//!   point but the last touches two moves, the start and the last one move
//!   each. Summing each point's two cheapest moves, plus the start's
//!   cheapest, counts every move of the path at most twice once the last
//!   point's second cheapest is taken out; as the last point is not known,
//!   the largest second cheapest is. Half that sum bounds the moves.
//!
//! The chip's planning of the moves (tens of microseconds a block) is left
//! out: the bound is what the stages and the detector need.

use super::duration::ScanTime;
use super::stage_targets;
use gonio_firmware::board::HeadConfig;
use gonio_firmware::motion::move_time;
use gonio_shared::ScanSpec;

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

/// The bound on the moves (s) and which of the two gave it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MoveBound {
    pub shortest_entry_s: f64,
    pub two_neighbours_s: f64,
}

/// The bound for `spec` from stage position `from` (microsteps), with
/// `settle_s` and `integration_s` of dwell per measured point, and the two
/// bounds on its moves.
pub fn lower_bound(cfg: &HeadConfig, spec: &ScanSpec, from: [i32; 3], settle_s: f64, integration_s: f64) -> (ScanTime, MoveBound) {
    let points: Vec<[i32; 3]> = (0..spec.theta_i_deg.len() as u32)
        .flat_map(|block| stage_targets(cfg, spec, block))
        .flatten()
        .collect();
    let n = points.len();
    let time = |a: [i32; 3], b: [i32; 3]| move_time(cfg, [0, 1, 2].map(|i| b[i] - a[i]));
    let mut start = f64::INFINITY;
    let mut cheapest = vec![Cheapest([f64::INFINITY; 2]); n];
    for (a, &p) in points.iter().enumerate() {
        let t = time(from, p);
        start = start.min(t);
        cheapest[a].offer(t);
        for b in a + 1..n {
            let t = time(p, points[b]);
            cheapest[a].offer(t);
            cheapest[b].offer(t);
        }
    }
    let entry: f64 = cheapest.iter().map(|c| c.0[0]).sum();
    // With one point its only move is from the start: the second cheapest
    // is infinite, and the entry bound is exact.
    let two = if n < 2 {
        entry
    } else {
        let both: f64 = cheapest.iter().map(|c| c.0[0] + c.0[1]).sum();
        let last = cheapest.iter().map(|c| c.0[1]).fold(0.0, f64::max);
        (both + start - last) / 2.0
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
    (time, moves)
}
