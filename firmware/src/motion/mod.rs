//! Moves: position bookkeeping in microsteps, trapezoidal profiles under the
//! axes' speed and acceleration limits (a chain of them where a sweep slows
//! down on its way, [`Level`]), and execution on the hardware step timer. A
//! move's steps are scheduled analytically ([`profile`]) and
//! compressed into `(interval, count, add)` blocks ([`blocks`]) that the
//! timer emits without the core touching single steps; all three axes start
//! at the same instant.

pub mod blocks;
pub mod executor;
pub mod profile;
pub mod step_irq;

use crate::config::{AxisConfig, HeadConfig};
use crate::hw::{Board, Hardware, StepTimer};
use crate::units;
use embassy_futures::select::{select, Either};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::{Axis, AxisAngles, Fault};
use profile::{Profile, MAX_LEVELS};

/// Slack (ms) beyond twice a move's scheduled duration before it counts as stalled.
const STALL_MARGIN_MS: u32 = 500;
/// Blocks planned between two yields to the executor: at most ~5 000
/// instructions each on the Cortex-M4 (`chip-bench`), so a stretch stays
/// well under the serve loop's budget of 100 000.
const YIELD_EVERY_BLOCKS: usize = 8;

/// Where homing leaves the axes (microsteps): 0° on every axis, the retro
/// direction at normal incidence, inside the travel. Plans start here.
pub const PARK: [i32; 3] = [0; 3];

/// Where the axes are, in microsteps from their zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Position {
    pub steps: [i32; 3],
    pub homed: [bool; 3],
    /// Direction (−1, 0, +1) of each axis in the move the step timer is
    /// running, until its steps are counted in: a move cut short by a stop
    /// is counted by [`halt`] instead of [`move_by`].
    pub in_flight: Option<[i8; 3]>,
}

impl Position {
    pub fn all_homed(&self) -> bool {
        self.homed.iter().all(|h| *h)
    }

    pub fn angles(&self, cfg: &HeadConfig) -> AxisAngles {
        axis_angles(cfg, self.steps)
    }
}

/// Stage angles of microstep positions.
pub fn axis_angles(cfg: &HeadConfig, steps: [i32; 3]) -> AxisAngles {
    AxisAngles {
        omega_deg: units::steps_to_deg(&cfg.axes[0], steps[0]),
        tau_deg: units::steps_to_deg(&cfg.axes[1], steps[1]),
        psi_deg: units::steps_to_deg(&cfg.axes[2], steps[2]),
    }
}

/// Target microsteps of stage angles.
pub fn target_steps(cfg: &HeadConfig, a: &AxisAngles) -> [i32; 3] {
    [
        units::deg_to_steps(&cfg.axes[0], a.omega_deg),
        units::deg_to_steps(&cfg.axes[1], a.tau_deg),
        units::deg_to_steps(&cfg.axes[2], a.psi_deg),
    ]
}

/// The analytical profile of an `n`-step move of an axis at up to `dps`.
pub fn trapezoid(axis: &AxisConfig, n: u32, dps: f32) -> Profile {
    ramp(axis, n, Limits::new(dps, axis.max_accel_dps2), &[])
}

/// The analytical profile of an `n`-step move of an axis within `limits`,
/// in stretches at fractions of its speed (`levels`; none: one stretch).
pub fn ramp(axis: &AxisConfig, n: u32, limits: Limits, levels: &[Level]) -> Profile {
    let (v, a) = step_rates(axis, limits);
    if levels.is_empty() {
        return Profile::new(n, v, a);
    }
    let caps = levels.iter().map(|l| {
        (
            libm::round(l.until.clamp(0.0, 1.0) as f64 * n as f64) as u32,
            v * l.scale.clamp(0.0, 1.0) as f64,
        )
    });
    Profile::levels(n, a, caps)
}

/// An axis's `limits` in microsteps: speed (steps/s) and acceleration
/// (steps/s²).
fn step_rates(axis: &AxisConfig, limits: Limits) -> (f64, f64) {
    let per_deg = axis.microsteps_per_rev as f64 / 360.0;
    (limits.speed_dps as f64 * per_deg, limits.accel_dps2 as f64 * per_deg)
}

/// A stretch of a move: up to `until`, a fraction (0–1) of its way, at most
/// `scale` (0–1) times its speed. Every axis runs the same stretches, so a
/// straight line in axis space stays one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    pub until: f32,
    pub scale: f32,
}

/// A move's stretches, in order.
pub type Levels = heapless::Vec<Level, MAX_LEVELS>;

/// The speed (deg/s) and acceleration (deg/s²) an axis moves with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    pub speed_dps: f32,
    pub accel_dps2: f32,
}

impl Limits {
    pub const fn new(speed_dps: f32, accel_dps2: f32) -> Self {
        Limits { speed_dps, accel_dps2 }
    }
}

/// Duration (s) of a move of every axis by `delta` microsteps at cruise speed.
pub fn move_time(cfg: &HeadConfig, delta: [i32; 3]) -> f64 {
    (0..3)
        .map(|i| {
            let axis = &cfg.axes[i];
            let (v, a) = step_rates(axis, Limits::new(axis.max_speed_dps, axis.max_accel_dps2));
            Profile::rest_to_rest_s(delta[i].unsigned_abs(), v, a)
        })
        .fold(0.0, f64::max)
}

/// Duration (s) of a move of every axis by `delta` microsteps within
/// per-axis `limits` and `levels`: the longest axis's profile.
pub fn profile_s(cfg: &HeadConfig, delta: [i32; 3], limits: [Limits; 3], levels: &[Level]) -> f64 {
    (0..3)
        .map(|i| ramp(&cfg.axes[i], delta[i].unsigned_abs(), limits[i], levels).duration())
        .fold(0.0, f64::max)
}

/// Blocks the move of every axis by `delta` microsteps at cruise speed takes
/// on a `tick_hz` step timer (what the chip plans before it starts).
pub fn move_blocks(cfg: &HeadConfig, delta: [i32; 3], tick_hz: u32) -> usize {
    let limits = cfg.axes.map(|a| Limits::new(a.max_speed_dps, a.max_accel_dps2));
    axis_blocks(cfg, delta, limits, &[], tick_hz).iter().sum()
}

/// Blocks each axis's profile of a move within `limits` and `levels` takes
/// on a `tick_hz` step timer: what [`plan`] queues, at most
/// [`executor::QUEUE`] an axis.
pub fn axis_blocks(cfg: &HeadConfig, delta: [i32; 3], limits: [Limits; 3], levels: &[Level], tick_hz: u32) -> [usize; 3] {
    [0, 1, 2].map(|i| {
        let t = ramp(&cfg.axes[i], delta[i].unsigned_abs(), limits[i], levels);
        blocks::ProfileBlocks::new(&t, tick_hz).count()
    })
}

/// Sets DIR and enables the drivers of the axes about to move, then waits the
/// driver's DIR setup time once for all of them.
async fn prepare<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, dirs: [Option<bool>; 3]) -> Result<(), Fault> {
    let mut any = false;
    for axis in Axis::ALL {
        if let Some(positive) = dirs[axis.index()] {
            let i = axis.index();
            let r = if positive { hw.dir[i].set_high() } else { hw.dir[i].set_low() };
            r.and_then(|_| hw.enable_n[i].set_low()).map_err(|_| Fault::Gpio)?;
            any = true;
        }
    }
    if any {
        hw.delay.delay_ns(units::seconds_to_ns(cfg.driver.dir_setup_s)).await;
    }
    Ok(())
}

/// A move the step timer runs, from [`plan`] to [`end`].
pub struct Running {
    delta: [i32; 3],
    /// Beyond this (ms) from its start the move counts as stalled.
    pub limit_ms: u32,
}

impl Running {
    /// Drops a move that outlasted its limit: the stall fault of its first
    /// moving axis. Where the axes stopped is no longer known: they need
    /// homing again.
    pub fn stalled<B: Board>(&self, hw: &mut Hardware<B>, pos: &mut Position) -> Fault {
        hw.steps.clear();
        pos.in_flight = None;
        pos.homed = [false; 3];
        let axis = Axis::ALL.into_iter().find(|a| self.delta[a.index()] != 0).unwrap_or(Axis::Rotation);
        Fault::StepTimer(axis)
    }
}

/// Plans a move of the axes by signed microstep counts within per-axis
/// `limits` and `levels`, all axes together: sets DIR, enables the drivers
/// and queues the blocks on the step timer, which [`start`] starts. Stretches
/// whose ramps need more blocks than the queue holds (very slow ones) give
/// way to the whole move at the slowest of them ([`slowest`]): two ramps.
pub async fn plan<B: Board>(
    hw: &mut Hardware<B>,
    cfg: &HeadConfig,
    delta: [i32; 3],
    limits: [Limits; 3],
    levels: &[Level],
) -> Result<Running, Fault> {
    let dirs = delta.map(|d| if d == 0 { None } else { Some(d > 0) });
    prepare(hw, cfg, dirs).await?;
    let mut levels = levels;
    let fallback = slowest(levels);
    if let Err(axis) = queue(hw, cfg, delta, limits, levels).await {
        if levels.is_empty() {
            return Err(Fault::StepTimer(axis));
        }
        levels = &fallback;
        queue(hw, cfg, delta, limits, levels).await.map_err(Fault::StepTimer)?;
    }
    // A move that outlasts its schedule by far means a stalled timer: stop it.
    let expected = profile_s(cfg, delta, limits, levels);
    Ok(Running {
        delta,
        limit_ms: (expected * 2.0 * 1e3).min(u32::MAX as f64 / 2.0) as u32 + STALL_MARGIN_MS,
    })
}

/// Queues the blocks of every axis's profile; the axis whose blocks the
/// queue could not hold (the queue then cleared).
async fn queue<B: Board>(
    hw: &mut Hardware<B>,
    cfg: &HeadConfig,
    delta: [i32; 3],
    limits: [Limits; 3],
    levels: &[Level],
) -> Result<(), Axis> {
    let tick_hz = <B::Steps as StepTimer>::TICK_HZ;
    hw.steps.clear();
    for axis in Axis::ALL {
        let i = axis.index();
        let t = ramp(&cfg.axes[i], delta[i].unsigned_abs(), limits[i], levels);
        for (j, b) in blocks::ProfileBlocks::new(&t, tick_hz).enumerate() {
            if hw.steps.push(axis, b).is_err() {
                hw.steps.clear();
                return Err(axis);
            }
            // Planning a long move takes a few million instructions on the
            // chip: let the executor run the link and the watchdog meanwhile.
            if j % YIELD_EVERY_BLOCKS == YIELD_EVERY_BLOCKS - 1 {
                embassy_futures::yield_now().await;
            }
        }
    }
    Ok(())
}

/// The whole move at the slowest of `levels`: what [`plan`] runs when their
/// blocks overflow the queue.
pub fn slowest(levels: &[Level]) -> [Level; 1] {
    let scale = levels.iter().map(|l| l.scale).fold(1.0, f32::min);
    [Level { until: 1.0, scale }]
}

/// Starts a planned move: its steps are in flight from now on.
pub fn start<B: Board>(hw: &mut Hardware<B>, pos: &mut Position, run: &Running) {
    pos.in_flight = Some(run.delta.map(|d| d.signum() as i8));
    hw.steps.start();
}

/// Ends a move whose steps the timer has `emitted`: counts them in, waits
/// the DIR hold time, and checks that every step was taken.
pub async fn end<B: Board>(
    hw: &mut Hardware<B>,
    cfg: &HeadConfig,
    pos: &mut Position,
    run: &Running,
    emitted: [u32; 3],
) -> Result<(), Fault> {
    count_in(pos, emitted);
    // DIR hold time before the next move may change it.
    hw.delay.delay_ns(units::seconds_to_ns(cfg.driver.dir_hold_s)).await;
    for axis in Axis::ALL {
        let i = axis.index();
        if emitted[i] != run.delta[i].unsigned_abs() {
            return Err(Fault::StepTimer(axis));
        }
    }
    Ok(())
}

/// Moves the axes by signed microstep counts at the given speeds (deg/s),
/// concurrently; updates `pos` by the steps actually emitted.
pub async fn move_by<B: Board>(
    hw: &mut Hardware<B>,
    cfg: &HeadConfig,
    pos: &mut Position,
    delta: [i32; 3],
    speed_dps: [f32; 3],
) -> Result<(), Fault> {
    let limits = [0, 1, 2].map(|i| Limits::new(speed_dps[i], cfg.axes[i].max_accel_dps2));
    let run = plan(hw, cfg, delta, limits, &[]).await?;
    start(hw, pos, &run);
    let emitted = match select(hw.steps.finished(), hw.delay.delay_ms(run.limit_ms)).await {
        Either::First(e) => e,
        Either::Second(()) => return Err(run.stalled(hw, pos)),
    };
    end(hw, cfg, pos, &run, emitted).await
}

/// Where the axes are while a move runs: `pos` plus the steps the timer has
/// emitted so far in the move's directions.
pub fn in_flight_steps(pos: &Position, emitted: [u32; 3]) -> [i32; 3] {
    let dirs = pos.in_flight.unwrap_or([0; 3]);
    [0, 1, 2].map(|i| pos.steps[i] + dirs[i] as i32 * emitted[i].min(i32::MAX as u32) as i32)
}

/// Adds the steps of the move in flight to the position.
fn count_in(pos: &mut Position, emitted: [u32; 3]) {
    if pos.in_flight.is_some() {
        pos.steps = in_flight_steps(pos, emitted);
        pos.in_flight = None;
    }
}

/// Stops the move in flight, if any (its future was dropped by a stop):
/// every axis decelerates from its current speed at its limit, and the
/// steps it took are counted in, so the axes stay homed.
pub async fn halt<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, pos: &mut Position) {
    if pos.in_flight.is_none() {
        return;
    }
    let tick_hz = <B::Steps as StepTimer>::TICK_HZ;
    hw.steps.brake([0, 1, 2].map(|i| units::brake_ticks(&cfg.axes[i], tick_hz)));
    // A brake takes at most the longest stop from full speed.
    let stop_s = cfg.axes.iter().map(|a| a.max_speed_dps / a.max_accel_dps2).fold(0.0, f32::max);
    let limit_ms = (stop_s * 2.0e3) as u32 + STALL_MARGIN_MS;
    match select(hw.steps.finished(), hw.delay.delay_ms(limit_ms)).await {
        Either::First(emitted) => count_in(pos, emitted),
        Either::Second(()) => {
            // A stalled timer: where the axes are is no longer known.
            hw.steps.clear();
            pos.in_flight = None;
            pos.homed = [false; 3];
        }
    }
    hw.delay.delay_ns(units::seconds_to_ns(cfg.driver.dir_hold_s)).await;
}

/// Moves every axis to absolute microstep targets at cruise speed.
pub async fn move_to<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, pos: &mut Position, target: [i32; 3]) -> Result<(), Fault> {
    let delta = [0, 1, 2].map(|i| target[i] - pos.steps[i]);
    let speed = [0, 1, 2].map(|i| cfg.axes[i].max_speed_dps);
    move_by(hw, cfg, pos, delta, speed).await
}
