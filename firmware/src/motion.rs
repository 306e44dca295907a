//! Moves: position bookkeeping in microsteps, step profiles, and execution
//! on the hardware step timer.
//!
//! A move ramps each axis linearly from a start rate to its cruise rate and
//! back, as three Klipper-style blocks (the `add` term changes the interval
//! by a constant each step), so the timer emits the whole move without the
//! core touching individual steps. All three axes start together.

use crate::board::{AxisConfig, HeadConfig};
use crate::hw::{Board, Hardware, StepBlock, StepTimer};
use crate::units;
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::{Axis, AxisAngles, Fault};

/// The start (and stop) rate is this fraction of the cruise rate.
const START_RATE_DIVISOR: u32 = 8;
/// Steps spent ramping from the start rate to cruise, at most.
const RAMP_STEPS: u32 = 400;

/// Where the axes are, in microsteps from their zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Position {
    pub steps: [i32; 3],
    pub homed: [bool; 3],
}

impl Position {
    pub fn all_homed(&self) -> bool {
        self.homed.iter().all(|h| *h)
    }

    pub fn angles(&self, cfg: &HeadConfig) -> AxisAngles {
        AxisAngles {
            omega_deg: units::steps_to_deg(&cfg.axes[0], self.steps[0]),
            tau_deg: units::steps_to_deg(&cfg.axes[1], self.steps[1]),
            psi_deg: units::steps_to_deg(&cfg.axes[2], self.steps[2]),
        }
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

/// The blocks of a move of `n` steps at cruise speed `dps`: ramp up, cruise,
/// ramp down. At most three blocks; empty ones are omitted.
pub fn profile(axis: &AxisConfig, n: u32, dps: f32, tick_hz: u32) -> heapless::Vec<StepBlock, 3> {
    let cruise = units::speed_to_interval(axis, dps, tick_hz);
    let start = cruise.saturating_mul(START_RATE_DIVISOR);
    let ramp = RAMP_STEPS.min(n / 2);
    let blocks = match (start - cruise).checked_div(ramp) {
        // One or two steps: no room to ramp, go at the start rate.
        None => [
            Some(StepBlock {
                interval: start,
                count: n,
                add: 0,
            }),
            None,
            None,
        ],
        Some(step) => {
            let add = step as i32;
            // The ramp ends one `add` above cruise; the ramp down mirrors it.
            let last_up = (start as i64 - add as i64 * (ramp as i64 - 1)).max(cruise as i64) as u32;
            [
                Some(StepBlock {
                    interval: start,
                    count: ramp,
                    add: -add,
                }),
                Some(StepBlock {
                    interval: cruise,
                    count: n - 2 * ramp,
                    add: 0,
                }),
                Some(StepBlock {
                    interval: last_up,
                    count: ramp,
                    add,
                }),
            ]
        }
    };
    let mut out = heapless::Vec::new();
    for b in blocks.into_iter().flatten().filter(|b| b.count > 0) {
        // At most three blocks fit the capacity of three.
        let _ = out.push(b);
    }
    out
}

/// Total ticks a block takes: `Σ_{k<count} (interval + k·add)`.
pub fn block_ticks(b: &StepBlock) -> u64 {
    let n = b.count as i64;
    (n * b.interval as i64 + b.add as i64 * n * (n - 1) / 2).max(0) as u64
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

/// Moves the axes by signed microstep counts at the given speeds (deg/s),
/// concurrently; updates `pos` by the steps actually emitted.
pub async fn move_by<B: Board>(
    hw: &mut Hardware<B>,
    cfg: &HeadConfig,
    pos: &mut Position,
    delta: [i32; 3],
    speed_dps: [f32; 3],
) -> Result<(), Fault> {
    let tick_hz = <B::Steps as StepTimer>::TICK_HZ;
    let dirs = delta.map(|d| if d == 0 { None } else { Some(d > 0) });
    prepare(hw, cfg, dirs).await?;
    hw.steps.clear();
    for axis in Axis::ALL {
        let i = axis.index();
        for b in profile(&cfg.axes[i], delta[i].unsigned_abs(), speed_dps[i], tick_hz) {
            if hw.steps.push(axis, b).is_err() {
                hw.steps.clear();
                return Err(Fault::StepTimer(axis));
            }
        }
    }
    let emitted = hw.steps.run().await;
    for axis in Axis::ALL {
        let i = axis.index();
        let e = emitted[i].min(delta[i].unsigned_abs()) as i32;
        pos.steps[i] += if delta[i] < 0 { -e } else { e };
        if e != delta[i].abs() {
            return Err(Fault::StepTimer(axis));
        }
    }
    Ok(())
}

/// Moves every axis to absolute microstep targets at cruise speed.
pub async fn move_to<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, pos: &mut Position, target: [i32; 3]) -> Result<(), Fault> {
    let delta = [0, 1, 2].map(|i| target[i] - pos.steps[i]);
    let speed = [0, 1, 2].map(|i| cfg.axes[i].max_speed_dps);
    move_by(hw, cfg, pos, delta, speed).await
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::REFERENCE;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn profile_emits_exactly_n_steps_with_positive_intervals(n in 0u32..200_000, dps in 0.5f32..30.0) {
            let ax = &REFERENCE.axes[2];
            let p = profile(ax, n, dps, 1_000_000);
            prop_assert_eq!(p.iter().map(|b| b.count).sum::<u32>(), n);
            for b in &p {
                let last = b.interval as i64 + b.add as i64 * (b.count as i64 - 1);
                prop_assert!(b.interval >= 1 && last >= 1);
            }
        }
    }
}
