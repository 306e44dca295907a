//! The trials of `safety-bench`, as a library so that a test
//! runs a few of them and checks the same bars; the binary's doc says what
//! each figure is.

use crate::stopping::{decel_s_max, duration_s, offset, ready, small_scan, status, trial, Activity, Stop, Trigger};
use gonio_firmware::config::REFERENCE;
use gonio_firmware::kinematics;
use gonio_frames::{scan_events, scan_frames, send};
use gonio_shared::icd::{AbortEndpoint, ContinueEndpoint, PauseEndpoint};
use gonio_shared::{Axis, Geometry, HeadState, ScanEvent, ScanSpec};
use gonio_sim::{Cue, FrameHead, SimConfig};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde_json::json;
use std::collections::BTreeMap;
use std::time::Instant;

const SEED: u64 = 17;

/// A reachable geometry at random.
fn geometry(rng: &mut StdRng) -> Geometry {
    loop {
        let g = Geometry::new(
            rng.random_range(0.0..70.0),
            rng.random_range(0.0..80.0),
            rng.random_range(-180.0..180.0),
        );
        if kinematics::inverse(&REFERENCE, &g).is_ok() {
            return g;
        }
    }
}

/// Worst figures of a set of stops.
#[derive(Default)]
struct Worst {
    trials: u32,
    laser_on_trials: u32,
    laser_off_ms: f64,
    stop_s: f64,
    position_error_steps: i64,
    speed_jump: f64,
    unsafe_after: u32,
}

impl Worst {
    fn add(&mut self, s: &Stop, laser_must_be_off: bool) {
        self.trials += 1;
        if s.laser_was_on {
            self.laser_on_trials += 1;
            self.laser_off_ms = self.laser_off_ms.max(s.laser_off_ms);
        }
        self.stop_s = self.stop_s.max(s.stop_s);
        self.position_error_steps = self.position_error_steps.max(s.position_error_steps);
        self.speed_jump = self.speed_jump.max(s.speed_jump);
        // After every stop: laser dark, drivers let go, nothing running.
        let st = &s.status;
        let at_rest = matches!(st.state, HeadState::Idle | HeadState::Paused { .. } | HeadState::Faulted);
        if (laser_must_be_off && st.laser_on) || st.drivers_enabled || !at_rest {
            self.unsafe_after += 1;
        }
    }

    fn json(&self) -> serde_json::Value {
        json!({
            "trials": self.trials,
            "laser_on_trials": self.laser_on_trials,
            "laser_off_ms_max": self.laser_off_ms,
            "stop_s_max": self.stop_s,
            "position_error_steps_max": self.position_error_steps,
            "speed_jump_max": self.speed_jump,
            "unsafe_after_stop": self.unsafe_after,
        })
    }
}

/// Positions a scan's events cover, each counted.
fn visits(events: &[(ScanEvent, &gonio_sim::Sent)], seen: &mut BTreeMap<u32, u32>) {
    for (e, _) in events {
        let index = match e {
            ScanEvent::Sample(s) => s.scan.map(|p| p.index),
            ScanEvent::Skipped { index, .. } => Some(*index),
            _ => None,
        };
        if let Some(i) = index {
            *seen.entry(i).or_default() += 1;
        }
    }
}

/// Every point of the small scan exactly once.
fn exactly_the_grid(seen: &BTreeMap<u32, u32>) -> bool {
    seen.len() as u32 == small_scan().len() && seen.values().all(|&n| n == 1)
}

/// A scan stopped mid-move by `how` (abort, then a new scan from the stop;
/// or pause, then continue), to its end: every point once, no homing, no
/// step lost. Tries later moments until one falls inside a move.
fn continued(head: &mut FrameHead, pause: bool) -> (bool, f64) {
    ready(head);
    let before = {
        let (st, _) = status(head);
        offset(head, &st)
    };
    for k in 0..40 {
        let tau = 2.0 + 0.137 * k as f64;
        let t0 = head.now() + 0.001;
        head.world_mut().step_log = Some(Vec::new());
        let stop = if pause {
            send::<PauseEndpoint>(&())
        } else {
            send::<AbortEndpoint>(&())
        };
        let scan = scan_frames(&small_scan()).into_iter().map(|f| (t0, Cue::Frame(f)));
        let sent = head.serve_timed(scan.chain([(t0 + tau, Cue::Frame(stop))]), t0 + tau + 1.0);
        let steps = head.world_mut().step_log.take().unwrap_or_default();
        let mid_move = steps.iter().any(|(_, t)| *t > t0 + tau) && steps.iter().any(|(_, t)| (t0 + tau - 0.01..t0 + tau).contains(t));
        let events = scan_events(&sent);
        let mut seen = BTreeMap::new();
        visits(&events, &mut seen);
        let next = events.iter().find_map(|(e, _)| match e {
            ScanEvent::Stopped { next_order, .. } | ScanEvent::Paused { next_order, .. } => Some(*next_order),
            _ => None,
        });
        let Some(next) = next else { continue };
        if !mid_move {
            // Not inside a move: clear the scan and try a later moment.
            let t = head.now();
            head.serve_timed([(t, Cue::Frame(send::<AbortEndpoint>(&())))], t + 0.01);
            continue;
        }
        let t = head.now();
        let resume = if pause {
            vec![send::<ContinueEndpoint>(&())]
        } else {
            scan_frames(&ScanSpec {
                first_order: next,
                ..small_scan()
            })
        };
        let sent = head.serve_timed(resume.into_iter().map(|f| (t, Cue::Frame(f))), t + 600.0);
        let events = scan_events(&sent);
        visits(&events, &mut seen);
        let finished = matches!(events.last(), Some((ScanEvent::Finished { .. }, _)));
        let after = status(head).0;
        let ok = finished && exactly_the_grid(&seen) && after.homed && offset(head, &after) == before;
        return (ok, tau);
    }
    (false, f64::NAN)
}

/// Runs the bench with `per_trigger` trials for each trigger; the JSON
/// object described in the `safety-bench` binary.
pub fn run(per_trigger: u32) -> serde_json::Value {
    let share = |f: f64| ((per_trigger as f64 * f).round() as u32).max(1);
    let (n_move, n_home, n_meas) = (share(0.64), share(0.08), share(0.14));
    let n_scan = per_trigger.saturating_sub(n_move + n_home + n_meas).max(1);
    let wall = Instant::now();
    let mut rng = StdRng::seed_from_u64(SEED);
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let home_s = duration_s(&mut head, Activity::Homing);
    let meas_s = duration_s(&mut head, Activity::Measurement);
    let scan_s = duration_s(&mut head, Activity::Scan);
    let mut by_trigger: BTreeMap<&str, Worst> = BTreeMap::new();
    let mut by_activity: BTreeMap<&str, Worst> = BTreeMap::new();
    let mut phases: BTreeMap<String, u32> = BTreeMap::new();
    let mut unhomed_by_homing_stop = 0u32;
    for trigger in Trigger::ALL {
        let plan = [("move", n_move), ("homing", n_home), ("measurement", n_meas), ("scan", n_scan)];
        // The host watch cannot be shorter than 1 s: silence trials pick
        // their moment from 1 s on, in moves that last longer.
        let lo = if trigger == Trigger::HostSilence { 1.0 } else { 0.005 };
        for (kind, n) in plan {
            for _ in 0..n {
                ready(&mut head);
                let (activity, length) = match kind {
                    "move" => {
                        let (st, _) = status(&mut head);
                        let at = gonio_firmware::motion::target_steps(&REFERENCE, &st.axes);
                        // A random reachable geometry at least `lo` + 50 ms
                        // away, and the analytical duration of the move there.
                        loop {
                            let g = geometry(&mut rng);
                            let axes = kinematics::inverse(&REFERENCE, &g).expect("reachable");
                            let target = gonio_firmware::motion::target_steps(&REFERENCE, &axes);
                            let length = gonio_firmware::motion::move_time(&REFERENCE, [0, 1, 2].map(|i| target[i] - at[i]));
                            if length > lo + 0.05 {
                                break (Activity::Move(g), length);
                            }
                        }
                    }
                    "homing" => (Activity::Homing, home_s),
                    "measurement" => (Activity::Measurement, meas_s),
                    _ => (Activity::Scan, scan_s),
                };
                let tau = rng.random_range(lo..length * 0.98);
                let s = trial(&mut head, activity, trigger, tau);
                for (axis, p) in &s.phases {
                    let name = format!("{}/{:?}", Axis::ALL[*axis].name(), p).to_lowercase();
                    *phases.entry(format!("{kind}:{name}")).or_default() += 1;
                }
                if kind == "homing" && !s.homed {
                    unhomed_by_homing_stop += 1;
                }
                by_trigger.entry(trigger.name()).or_default().add(&s, true);
                by_activity.entry(kind).or_default().add(&s, true);
            }
            eprintln!("{} / {kind}: done ({:.0} s)", trigger.name(), wall.elapsed().as_secs_f64());
        }
    }
    let (continue_after_abort_ok, abort_tau) = continued(&mut head, false);
    let (pause_continue_ok, pause_tau) = continued(&mut head, true);
    let all = by_trigger.values().fold(Worst::default(), |mut a, w| {
        a.trials += w.trials;
        a.laser_on_trials += w.laser_on_trials;
        a.laser_off_ms = a.laser_off_ms.max(w.laser_off_ms);
        a.stop_s = a.stop_s.max(w.stop_s);
        a.position_error_steps = a.position_error_steps.max(w.position_error_steps);
        a.speed_jump = a.speed_jump.max(w.speed_jump);
        a.unsafe_after += w.unsafe_after;
        a
    });
    let decel = decel_s_max();
    let bars = json!({
        "laser_off_ms_max": all.laser_off_ms <= 1.0,
        "stop_s_max": all.stop_s <= decel + 0.010,
        "position_error_steps_max": all.position_error_steps == 0,
        "speed_jump_max": all.speed_jump <= 1.05,
        "continue_after_abort_ok": continue_after_abort_ok,
        "pause_continue_ok": pause_continue_ok,
        "safe_after_every_stop": all.unsafe_after == 0,
        // The moments reached every axis in every phase of its moves.
        "every_axis_phase_stopped": Axis::ALL.iter().all(|a| ["acceleration", "cruise", "deceleration"]
            .iter()
            .all(|p| phases.get(&format!("move:{}/{p}", a.name())).is_some_and(|&n| n > 0))),
    });
    let met = bars.as_object().is_some_and(|b| b.values().all(|v| v.as_bool() == Some(true)));
    let out = json!({
        "trials": all.trials,
        "trials_per_trigger": per_trigger,
        "laser_off_ms_max": all.laser_off_ms,
        "laser_on_trials": all.laser_on_trials,
        "stop_s_max": all.stop_s,
        "decel_s_max": decel,
        "position_error_steps_max": all.position_error_steps,
        "speed_jump_max": all.speed_jump,
        "continue_after_abort_ok": continue_after_abort_ok,
        "continue_after_abort_moment_s": abort_tau,
        "pause_continue_ok": pause_continue_ok,
        "pause_continue_moment_s": pause_tau,
        "unsafe_after_stop": all.unsafe_after,
        "homing_stops_leaving_axes_unhomed": unhomed_by_homing_stop,
        "by_trigger": by_trigger.iter().map(|(k, w)| (k.to_string(), w.json())).collect::<serde_json::Map<_, _>>(),
        "by_activity": by_activity.iter().map(|(k, w)| (k.to_string(), w.json())).collect::<serde_json::Map<_, _>>(),
        "moments_by_axis_phase": phases,
        "activity_durations_s": {"homing": home_s, "measurement": meas_s, "scan": scan_s},
        "sim_slice_s": gonio_sim::clock::SLICE_S,
        "seed": SEED,
        "bars": bars,
        "all_bars_met": met,
        "wall_s": wall.elapsed().as_secs_f64(),
    });
    out
}
