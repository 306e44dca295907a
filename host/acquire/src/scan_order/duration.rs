//! What a visit order costs in head time: the moves under the axis limits,
//! the chip's planning of them, and the dwell at every measured point.

use gonio_firmware::config::HeadConfig;
use gonio_firmware::kinematics;
use gonio_firmware::motion::blocks::plan_s;
use gonio_firmware::motion::executor::QUEUE;
use gonio_firmware::motion::{axis_blocks, move_blocks, move_time, profile_s, slowest, target_steps};
use gonio_firmware::sweep;
use gonio_shared::{DetectionReport, Geometry, ScanSpec, Visit};

/// The step timer's tick rate on the reference board (chip/step_timer.rs).
const STEP_TICK_HZ: u32 = 1_000_000;

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
    /// Counts a move of the axes by `delta` microsteps at cruise speed and
    /// the chip's planning of it.
    fn add_move(&mut self, cfg: &HeadConfig, delta: [i32; 3]) {
        self.moves_s += move_time(cfg, delta);
        self.planning_s += plan_s(move_blocks(cfg, delta, STEP_TICK_HZ));
    }

    /// Counts a point at `g` visited from stage position `at` (which it
    /// moves to the point's): the move, `settle_s` and `integration_s`; or
    /// a point skipped without moving, where the kinematics cannot reach it.
    fn add_point(&mut self, cfg: &HeadConfig, at: &mut [i32; 3], g: &Geometry, settle_s: f64, integration_s: f64) {
        match kinematics::inverse(cfg, g) {
            Ok(axes) => {
                let target = target_steps(cfg, &axes);
                self.add_move(cfg, [0, 1, 2].map(|i| target[i] - at[i]));
                *at = target;
                self.settle_s += settle_s;
                self.integration_s += integration_s;
                self.measured += 1;
            }
            Err(_) => self.skipped += 1,
        }
    }

    pub fn total_s(&self) -> f64 {
        self.moves_s + self.planning_s + self.settle_s + self.integration_s
    }
}

/// Settle and acquisition time per point (s) under detection settings
/// `det`: the acquisition counts the chop periods the detector spends ranging
/// the gain and letting the amplifier settle.
pub fn dwell_s(det: &DetectionReport) -> (f64, f64) {
    let settle = det.settle_periods as f64;
    let extra_periods = if det.settings.auto_range { 2.0 * settle + 1.0 } else { settle };
    let acquire = det.integration_s as f64 + extra_periods / det.chop_hz_actual as f64;
    (det.settings.settle_s as f64, acquire)
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
    scan_steps(cfg, spec, visit, from, (settle_s, integration_s), &mut t, |_| {});
    t
}

/// [`scan_time`], calling `after` with the running total after each position.
fn scan_steps(
    cfg: &HeadConfig,
    spec: &ScanSpec,
    visit: impl Iterator<Item = u32>,
    from: [i32; 3],
    (settle_s, integration_s): (f64, f64),
    t: &mut ScanTime,
    mut after: impl FnMut(&ScanTime),
) {
    let mut at = from;
    for i in visit {
        if let Some(g) = spec.point(i) {
            t.add_point(cfg, &mut at, &g, settle_s, integration_s);
        }
        after(t);
    }
}

/// Duration of a sweep scan's positions in the order `visit` yields them,
/// from stage position `from`, as the head runs them (`Head::sweep_turn`):
/// a retro point as [`scan_time`] counts a point (the move, `settle_s`,
/// `acquire_s`); a row as the move to its start, `settle_s`, `prepare_s` to
/// range the detector, then the arm's sweep at the row's speed, slower
/// across the lobes (`sweep::row_levels`, for samples of its periods at
/// `chop_hz`). Positions that cannot be reached are skipped without moving.
/// `integration_s` holds the sweeps and the points' acquisitions.
pub fn sweep_time(
    cfg: &HeadConfig,
    spec: &ScanSpec,
    visit: impl Iterator<Item = u32>,
    from: [i32; 3],
    dwell: (f64, f64, f64),
    chop_hz: f32,
) -> ScanTime {
    let mut t = ScanTime::default();
    sweep_steps(cfg, spec, visit, from, dwell, chop_hz, &mut t, |_| {});
    t
}

/// [`sweep_time`], calling `after` with the running total after each position.
#[allow(clippy::too_many_arguments)]
fn sweep_steps(
    cfg: &HeadConfig,
    spec: &ScanSpec,
    visit: impl Iterator<Item = u32>,
    from: [i32; 3],
    (settle_s, acquire_s, prepare_s): (f64, f64, f64),
    chop_hz: f32,
    t: &mut ScanTime,
    mut after: impl FnMut(&ScanTime),
) {
    let mut at = from;
    for (order, i) in (spec.first_order..).zip(visit) {
        match spec.visit(i, order) {
            Some(Visit::Row(row)) => sweep_row(cfg, &row, chop_hz, (settle_s, prepare_s), &mut at, t),
            Some(Visit::Point(g)) => t.add_point(cfg, &mut at, &g, settle_s, acquire_s),
            None => {}
        }
        after(t);
    }
}

/// One row of a sweep scan from stage position `at` (left at its end).
fn sweep_row(
    cfg: &HeadConfig,
    row: &gonio_shared::SweepRow,
    chop_hz: f32,
    (settle_s, prepare_s): (f64, f64),
    at: &mut [i32; 3],
    t: &mut ScanTime,
) {
    let Ok(p) = sweep::row_plan(cfg, row, chop_hz) else {
        t.skipped += 1;
        return;
    };
    let (to_start, across, limits) = ([0, 1, 2].map(|k| p.start[k] - at[k]), p.delta(), p.limits);
    // As `motion::plan` queues it: the stretches, or the slowest all
    // along where they overflow the queue; planned before the arm starts.
    let fallback = slowest(&p.levels);
    let mut blocks = axis_blocks(cfg, across, limits, &p.levels, STEP_TICK_HZ);
    let levels = match blocks.iter().all(|&b| b <= QUEUE) {
        true => &p.levels[..],
        false => {
            blocks = axis_blocks(cfg, across, limits, &fallback, STEP_TICK_HZ);
            &fallback[..]
        }
    };
    t.planning_s += plan_s(blocks.iter().sum());
    t.add_move(cfg, to_start);
    t.settle_s += settle_s + prepare_s;
    t.integration_s += profile_s(cfg, across, limits, levels);
    t.measured += 1;
    *at = p.end;
}

/// The head time still to run before each position of `spec` from its
/// `first_order` in the order `visit` yields them (s), then 0 after the last:
/// element 0 is the whole estimate. The dwell is the detection's
/// ([`dwell_s`]), a sweep scan's rows as [`sweep_time`] counts them.
pub fn time_left_s(cfg: &HeadConfig, spec: &ScanSpec, visit: impl Iterator<Item = u32>, from: [i32; 3], det: &DetectionReport) -> Vec<f64> {
    let (settle, acquire) = dwell_s(det);
    let mut done = vec![0.0];
    let mut t = ScanTime::default();
    let record = |t: &ScanTime| done.push(t.total_s());
    if spec.sweep.is_some() {
        let ranging = acquire - det.integration_s as f64;
        sweep_steps(
            cfg,
            spec,
            visit,
            from,
            (settle, acquire, ranging),
            det.settings.chop_hz,
            &mut t,
            record,
        );
    } else {
        scan_steps(cfg, spec, visit, from, (settle, acquire), &mut t, record);
    }
    let total = t.total_s();
    done.into_iter().map(|d| total - d).collect()
}
