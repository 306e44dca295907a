//! Scan planning and timing. Planning lives on the device: it expands the
//! grid itself, one point at a time, so a scan needs no list from the host
//! and survives a slow host. Within each incidence angle, the unreachable
//! points come first (they cost no motion) and the reachable ones follow in
//! nearest-neighbour order of *move time* under the axis limits, starting
//! from where the previous incidence ended. The choice is deterministic, so
//! the host replays it to estimate the duration and a resumed scan replays
//! it up to its first position. An incidence with more points than
//! [`PLAN_CAPACITY`] falls back to the serpentine of `ScanSpec::index_at_order`.

use super::{move_time, target_steps};
use crate::board::HeadConfig;
use crate::kinematics;
use gonio_shared::ScanSpec;

/// Points of one incidence angle planned nearest-neighbour (a bitset of 512 bytes).
pub const PLAN_CAPACITY: usize = 4096;

/// Where a scan is and what it has visited of the current incidence.
pub struct Planner {
    /// Visit position of the next point.
    order: u32,
    block: u32,
    block_len: u32,
    done_in_block: u32,
    visited: [u32; PLAN_CAPACITY / 32],
    /// Stage position (microsteps) after the last reachable point.
    at: [i32; 3],
}

impl Planner {
    /// A plan for `spec` starting from stage position `from` (microsteps).
    pub fn new(spec: &ScanSpec, from: [i32; 3]) -> Self {
        let n_ti = spec.theta_i_deg.len().max(1) as u32;
        Planner {
            order: 0,
            block: 0,
            block_len: spec.len() / n_ti,
            done_in_block: 0,
            visited: [0; PLAN_CAPACITY / 32],
            at: from,
        }
    }

    /// Visit position of the point [`Planner::next`] returns next.
    pub fn order(&self) -> u32 {
        self.order
    }

    fn seen(&self, k: u32) -> bool {
        self.visited[(k / 32) as usize] & (1 << (k % 32)) != 0
    }

    fn mark(&mut self, k: u32) {
        self.visited[(k / 32) as usize] |= 1 << (k % 32);
    }

    /// The canonical index of the next point to visit, or `None` at the end.
    pub fn next(&mut self, cfg: &HeadConfig, spec: &ScanSpec) -> Option<u32> {
        if self.order >= spec.len() {
            return None;
        }
        if self.done_in_block == self.block_len {
            self.block += 1;
            self.done_in_block = 0;
            self.visited = [0; PLAN_CAPACITY / 32];
        }
        let base = self.block * self.block_len;
        let index = if self.block_len as usize > PLAN_CAPACITY {
            spec.index_at_order(self.order)?
        } else {
            let reach = |k: u32| spec.point(base + k).and_then(|g| kinematics::inverse(cfg, &g).ok());
            let unreachable = (0..self.block_len).find(|&k| !self.seen(k) && reach(k).is_none());
            let k = match unreachable {
                Some(k) => k,
                None => {
                    let mut best: Option<(f64, u32, [i32; 3])> = None;
                    for k in (0..self.block_len).filter(|&k| !self.seen(k)) {
                        let Some(axes) = reach(k) else { continue };
                        let target = target_steps(cfg, &axes);
                        let t = move_time(cfg, [0, 1, 2].map(|i| target[i] - self.at[i]));
                        if best.is_none_or(|(bt, _, _)| t < bt) {
                            best = Some((t, k, target));
                        }
                    }
                    let (_, k, target) = best?;
                    self.at = target;
                    k
                }
            };
            self.mark(k);
            base + k
        };
        self.done_in_block += 1;
        self.order += 1;
        Some(index)
    }
}

/// Time budget of a scan (s).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ScanTime {
    pub moves_s: f64,
    pub settle_s: f64,
    pub integration_s: f64,
    pub measured: u32,
    pub skipped: u32,
}

impl ScanTime {
    pub fn total_s(&self) -> f64 {
        self.moves_s + self.settle_s + self.integration_s
    }
}

/// Duration of the points of `spec` in the order `visit` yields them (canonical
/// indices), starting from stage position `from` (microsteps); unreachable
/// points are skipped without moving, as the head does.
pub fn scan_time(
    cfg: &HeadConfig,
    spec: &ScanSpec,
    visit: impl Iterator<Item = u32>,
    from: [i32; 3],
    settle_s: f64,
    integration_s: f64,
) -> ScanTime {
    let mut t = ScanTime::default();
    let mut at = from;
    for g in visit.filter_map(|i| spec.point(i)) {
        match kinematics::inverse(cfg, &g) {
            Ok(axes) => {
                let target = target_steps(cfg, &axes);
                t.moves_s += move_time(cfg, [0, 1, 2].map(|i| target[i] - at[i]));
                at = target;
                t.settle_s += settle_s;
                t.integration_s += integration_s;
                t.measured += 1;
            }
            Err(_) => t.skipped += 1,
        }
    }
    t
}

/// The head's visit order of a whole scan, from `from` (the host's replay).
pub fn visit_order<'a>(cfg: &'a HeadConfig, spec: &'a ScanSpec, from: [i32; 3]) -> impl Iterator<Item = u32> + 'a {
    let mut p = Planner::new(spec, from);
    core::iter::from_fn(move || p.next(cfg, spec))
}
