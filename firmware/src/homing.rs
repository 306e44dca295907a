//! Homing on a switch at the negative end of each axis: fast approach in
//! chunks until the switch closes, back off until it opens, re-approach
//! slowly in microstep-sized chunks, then find the switch's edge to the
//! microstep (off it one microstep at a time, and back on), and set the
//! position to the switch angle. The switch is read between chunks, so the
//! fast approach overshoots by at most one chunk (taken up by the back-off);
//! the last approach does not overshoot, so homing repeats to the
//! microstep and a stop that re-homes an axis leaves no offset behind.
//! Each read waits for the switch's input filter after the chunk's last
//! step ([`SWITCH_SETTLE_S`]): read at once, it would show the level from
//! before that step, and the edge would be found a microstep late.

use crate::config::HeadConfig;
use crate::hw::{Board, Hardware};
use crate::motion::{move_by, Position};
use crate::units;
use embedded_hal::digital::InputPin;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::{Axis, Fault};

/// Fast approach chunk (degrees).
const FAST_CHUNK_DEG: f32 = 0.5;
/// Slow re-approach chunk (microsteps).
const SLOW_CHUNK_STEPS: i32 = 4;
/// Time for a home input to follow its switch before it is read: the
/// board's RC filter (4.7 kΩ, 100 nF: τ = 0.47 ms, chip/pins.rs) within
/// 1 % of its final level after five time constants.
pub const SWITCH_SETTLE_S: f32 = 2.5e-3;

fn pressed<B: Board>(hw: &mut Hardware<B>, axis: Axis) -> Result<bool, Fault> {
    hw.home[axis.index()].is_high().map_err(|_| Fault::HomeSwitchNotFound(axis))
}

/// One homing sweep: step `chunk` microsteps at a time (negative = towards
/// the switch) at `speed_dps` until the switch reads `until`, for at most
/// `limit` microsteps.
struct Sweep {
    axis: Axis,
    chunk: i32,
    speed_dps: f32,
    until: bool,
    limit: u32,
}

/// Runs a sweep; returns whether the switch reached the wanted state.
async fn sweep<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, pos: &mut Position, s: Sweep) -> Result<bool, Fault> {
    let i = s.axis.index();
    let mut travelled = 0u32;
    while pressed(hw, s.axis)? != s.until {
        if travelled >= s.limit {
            return Ok(false);
        }
        let mut delta = [0; 3];
        delta[i] = s.chunk;
        let mut speed = [0.0; 3];
        speed[i] = s.speed_dps;
        move_by(hw, cfg, pos, delta, speed).await?;
        hw.delay.delay_ns(units::seconds_to_ns(SWITCH_SETTLE_S)).await;
        travelled += s.chunk.unsigned_abs();
    }
    Ok(true)
}

/// Homes one axis. On success the axis is at its switch angle and marked homed.
pub async fn home_axis<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, pos: &mut Position, axis: Axis) -> Result<(), Fault> {
    let c = cfg.axis(axis);
    let i = axis.index();
    pos.homed[i] = false;
    // Full travel plus margin: from anywhere, the switch must be met within it.
    let travel = units::deg_to_steps(c, c.max_deg - c.home_deg + 2.0 * c.home_backoff_deg).unsigned_abs();
    let fast = -units::deg_to_steps(c, FAST_CHUNK_DEG).max(1);
    let approach = Sweep {
        axis,
        chunk: fast,
        speed_dps: c.max_speed_dps,
        until: true,
        limit: travel,
    };
    if !sweep(hw, cfg, pos, approach).await? {
        return Err(Fault::HomeSwitchNotFound(axis));
    }
    let backoff = units::deg_to_steps(c, c.home_backoff_deg).unsigned_abs();
    let release = Sweep {
        axis,
        chunk: -fast,
        speed_dps: c.max_speed_dps,
        until: false,
        limit: backoff,
    };
    if !sweep(hw, cfg, pos, release).await? {
        return Err(Fault::HomeSwitchStuck(axis));
    }
    let touch = Sweep {
        axis,
        chunk: -SLOW_CHUNK_STEPS,
        speed_dps: c.home_slow_dps,
        until: true,
        limit: 2 * backoff,
    };
    if !sweep(hw, cfg, pos, touch).await? {
        return Err(Fault::HomeSwitchNotFound(axis));
    }
    let edge = |chunk: i32, until: bool| Sweep {
        axis,
        chunk,
        speed_dps: c.home_slow_dps,
        until,
        limit: 2 * SLOW_CHUNK_STEPS as u32,
    };
    if !sweep(hw, cfg, pos, edge(1, false)).await? {
        return Err(Fault::HomeSwitchStuck(axis));
    }
    if !sweep(hw, cfg, pos, edge(-1, true)).await? {
        return Err(Fault::HomeSwitchNotFound(axis));
    }
    pos.steps[i] = units::deg_to_steps(c, c.home_deg);
    pos.homed[i] = true;
    Ok(())
}
