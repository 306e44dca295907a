//! `cargo run --release -p gonio-bench --bin safety-bench [TRIALS_PER_TRIGGER]`:
//! how fast and how surely the head stops, one JSON object on stdout (progress on stderr).
//!
//! The firmware on the simulated head, in simulated time, is stopped at
//! randomised moments (default 1 000 per trigger: 640 in moves between
//! random reachable geometries, every axis in acceleration, cruise and
//! deceleration, 80 in homing, 140 in a measurement with the laser on, 140
//! in a scan) by each trigger: an abort request, the link closing, the host
//! falling silent (its watch set to the moment), the E-STOP opening. One
//! head serves every trial, never re-homed except after a stop in homing, so
//! a lost or doubled step would show in every later trial.
//!
//! - `laser_off_ms_max`: trigger → laser enable low, over trials where the
//!   laser was on (measurements, scans); bar ≤ 1.0.
//! - `stop_s_max`: trigger → last step; bar ≤ `decel_s_max` + 10 ms.
//! - `position_error_steps_max`: change of (firmware position − motor
//!   position) over a trial; bar 0.
//! - `speed_jump_max`: largest step-interval change relative to a ramp at
//!   the axis's acceleration limit, over the stop and the 4 steps before it
//!   (`gonio_tests::stopping::speed_jump`); bar ≤ 1.05.
//! - `continue_after_abort_ok`: a scan aborted mid-move, then continued from
//!   its `Stopped` position, stores every point once, without homing.
//! - `pause_continue_ok`: the same with pause and continue, the head
//!   holding the scan (no replanning).
//! - `every_axis_phase_stopped`: moves were stopped on every axis in its
//!   acceleration, its cruise and its deceleration (`moments_by_axis_phase`);
//!   `safe_after_every_stop`: laser off, drivers disabled, nothing running
//!   after each stop. `all_bars_met` says whether every bar holds.

fn main() {
    let per_trigger: u32 = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(1000);
    let out = gonio_tests::safety_trials::run(per_trigger);
    println!("{}", serde_json::to_string_pretty(&out).expect("JSON"));
}
