//! A scan's visit order, planned on the host and streamed to the head in
//! chunks (`gonio/plan`). Within each incidence angle, the unreachable points
//! come first (they cost no motion) and the reachable ones follow in
//! nearest-neighbour order of *move time* under the axis limits, starting
//! from where the previous incidence ended. The choice is deterministic, so
//! the duration estimate and a resumed scan follow the same order; an
//! incidence with more points than [`PLAN_CAPACITY`] falls back to the
//! serpentine of `ScanSpec::index_at_order`.
//!
//! Why here and not on the head: measured on the Cortex-M4 (`chip-bench`),
//! one step of this plan over a 4 096-point incidence costs hundreds of
//! millions of instructions in soft-float f64 (seconds, past the watchdog),
//! and a resume would replay the plan up to its position; the host does the
//! whole Belcour grid in well under a second, and the head only keeps a
//! bounded queue of the next points (`PLAN_QUEUE`).

use gonio_firmware::board::HeadConfig;
use gonio_firmware::kinematics;
use gonio_firmware::motion::blocks::plan_s;
use gonio_firmware::motion::{move_blocks, move_time, target_steps};

/// The step timer's tick rate on the reference board (chip/step_timer.rs).
const STEP_TICK_HZ: u32 = 1_000_000;
use gonio_shared::ScanSpec;

/// Points of one incidence angle planned nearest-neighbour.
pub const PLAN_CAPACITY: usize = 4096;

/// Where a scan is and what it has visited of the current incidence.
pub struct Planner {
    /// Visit position of the next point.
    order: u32,
    block: u32,
    block_len: u32,
    done_in_block: u32,
    /// Stage targets of the current incidence's points (`None`: unreachable),
    /// computed once per incidence, and which were visited.
    targets: Vec<Option<[i32; 3]>>,
    visited: Vec<bool>,
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
            targets: Vec::new(),
            visited: Vec::new(),
            at: from,
        }
    }

    /// The canonical index of the next point to visit, or `None` at the end.
    pub fn next(&mut self, cfg: &HeadConfig, spec: &ScanSpec) -> Option<u32> {
        if self.order >= spec.len() {
            return None;
        }
        if self.done_in_block == self.block_len {
            self.block += 1;
            self.done_in_block = 0;
            self.targets.clear();
        }
        let base = self.block * self.block_len;
        let index = if self.block_len as usize > PLAN_CAPACITY {
            spec.index_at_order(self.order)?
        } else {
            if self.targets.is_empty() {
                self.targets = (0..self.block_len)
                    .map(|k| {
                        let g = spec.point(base + k)?;
                        kinematics::inverse(cfg, &g).ok().map(|axes| target_steps(cfg, &axes))
                    })
                    .collect();
                self.visited = vec![false; self.block_len as usize];
            }
            let open = |k: &usize| !self.visited[*k];
            let k = match (0..self.targets.len()).filter(open).find(|&k| self.targets[k].is_none()) {
                Some(k) => k,
                None => {
                    let mut best: Option<(f64, usize)> = None;
                    for k in (0..self.targets.len()).filter(open) {
                        let Some(target) = self.targets[k] else { continue };
                        let t = move_time(cfg, [0, 1, 2].map(|i| target[i] - self.at[i]));
                        if best.is_none_or(|(bt, _)| t < bt) {
                            best = Some((t, k));
                        }
                    }
                    let (_, k) = best?;
                    self.at = self.targets[k]?;
                    k
                }
            };
            self.visited[k] = true;
            base + k as u32
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
    /// The chip's planning of the moves ([`gonio_firmware::motion::blocks::plan_s`]).
    pub planning_s: f64,
    pub settle_s: f64,
    pub integration_s: f64,
    pub measured: u32,
    pub skipped: u32,
}

impl ScanTime {
    pub fn total_s(&self) -> f64 {
        self.moves_s + self.planning_s + self.settle_s + self.integration_s
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
                let delta = [0, 1, 2].map(|i| target[i] - at[i]);
                t.moves_s += move_time(cfg, delta);
                t.planning_s += plan_s(move_blocks(cfg, delta, STEP_TICK_HZ));
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

/// The visit order of a whole scan, from `from`.
pub fn visit_order<'a>(cfg: &'a HeadConfig, spec: &'a ScanSpec, from: [i32; 3]) -> impl Iterator<Item = u32> + 'a {
    let mut p = Planner::new(spec, from);
    core::iter::from_fn(move || p.next(cfg, spec))
}
