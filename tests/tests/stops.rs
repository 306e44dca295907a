//! Stop means stop: the step executor's brake on its own, and
//! the firmware on the simulated head stopped in the middle of a move, a
//! measurement and a scan by an abort, the E-STOP and the idle watch; a
//! paused scan continued. docs/faults.md#stops states what is checked.

use gonio_firmware::config::REFERENCE;
use gonio_firmware::hw::StepBlock;
use gonio_firmware::motion::blocks::{self, profile_blocks};
use gonio_firmware::motion::executor::Executor;
use gonio_firmware::{motion, units};
use gonio_frames::{replies, scan_events, scan_frames, send};
use gonio_shared::icd::{
    ContinueEndpoint, HomeEndpoint, HomeRequest, MeasureEndpoint, MeasureRequest, MoveEndpoint, PauseEndpoint, SafetyEndpoint,
    StatusEndpoint,
};
use gonio_shared::{Fault, Geometry, HeadState, SafetySettings, ScanEvent};
use gonio_sim::{Cue, FrameHead, SimConfig};
use gonio_tests::stopping::{
    accel_steps, decel_s_max, ready, small_scan, small_sweep_scan, speed_jump, swept_rows, trial, Activity, Trigger,
};
use std::cell::Cell;
use std::convert::Infallible;
use std::rc::Rc;

/// A STEP pin that counts its rising edges.
struct Counting(Rc<Cell<u32>>);

impl embedded_hal::digital::ErrorType for Counting {
    type Error = Infallible;
}

impl embedded_hal::digital::OutputPin for Counting {
    fn set_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.set(self.0.get() + 1);
        Ok(())
    }
}

/// The arm's full-speed move of `n` steps on a 1 MHz executor, braked at
/// event `brake_at`; returns the step times (s), the brake's time and the
/// steps the pin saw.
fn braked_move(n: u32, brake_at: usize) -> (Vec<f64>, f64, u32, [u32; 3]) {
    let axis = &REFERENCE.axes[2];
    let edges = Rc::new(Cell::new(0));
    let pins = [
        Counting(Rc::new(Cell::new(0))),
        Counting(Rc::new(Cell::new(0))),
        Counting(edges.clone()),
    ];
    let mut exec = Executor::new(pins, 3);
    let t = motion::trapezoid(axis, n, axis.max_speed_dps);
    let mut blocks: Vec<StepBlock> = Vec::new();
    assert!(profile_blocks(&t, 1_000_000, |b| {
        blocks.push(b);
        true
    }));
    for b in blocks {
        exec.push(gonio_shared::Axis::Arm, b).unwrap();
    }
    let brake = [0, 1, 2].map(|i| units::brake_ticks(&REFERENCE.axes[i], 1_000_000));
    let (mut times, mut braked_s) = (Vec::new(), f64::NAN);
    let mut next = exec.start();
    let mut event = 0;
    while let Some(tick) = next {
        let before = exec.emitted()[2];
        next = exec.fire(tick);
        if exec.emitted()[2] > before {
            times.push(tick as f64 * 1e-6);
        }
        event += 1;
        if event == brake_at {
            braked_s = tick as f64 * 1e-6;
            next = exec.brake(brake);
        }
    }
    (times, braked_s, edges.get(), exec.emitted())
}

#[test]
fn a_brake_at_any_moment_of_a_move_slows_at_the_limit_without_skipping_a_step() {
    let axis = &REFERENCE.axes[2];
    let a = accel_steps(axis);
    let n = 40_000; // 100° of the arm: accelerating, cruising, decelerating
    let (full, _, _, _) = braked_move(n, usize::MAX);
    assert_eq!(full.len() as u32, n);
    let events = 2 * n as usize;
    let v = axis.max_speed_dps as f64 * axis.steps_per_deg() as f64;
    for k in 1..40 {
        let at = events * k / 40;
        let (times, braked_s, edges, emitted) = braked_move(n, at);
        assert_eq!(edges, emitted[2], "a step counted that the pin did not see");
        assert!(emitted[2] <= n, "the brake ran past the move's end");
        let jump = speed_jump(&times, a);
        assert!(jump <= 1.05, "brake at event {at}: speed jump {jump}");
        let stop = times.last().unwrap() - braked_s;
        assert!(stop <= v / a + 0.01, "brake at event {at}: stopped after {stop} s");
    }
    // Braked in the cruise, the axis stops within v²/2a steps (plus the one
    // already scheduled) of where it was.
    let (times, braked_s, _, emitted) = braked_move(n, events / 2);
    let before = times.iter().filter(|&&t| t <= braked_s).count() as f64;
    let after = emitted[2] as f64 - before;
    assert!((after - v * v / (2.0 * a)).abs() <= 2.0, "{after} steps after the brake");
}

/// A host that stops reading while a row is swept (the head's sends wait,
/// as on a full USB queue) does not hold the E-STOP back: the laser goes
/// off at once, not once the send is through (491 ms later when the send
/// was not raced against it), and the head stays homed. (The simulated
/// stages advance with the detector's reads, so they stand while the send
/// waits: the brake's timing is the other stop tests'.)
#[test]
fn an_estop_while_a_swept_sample_waits_to_be_sent_stops_at_once() {
    let mut head = FrameHead::new(&SimConfig::default());
    let (_, rows) = swept_rows(&mut head);
    let (first, last) = rows[0];
    ready(&mut head);
    // The trial's clock starts a millisecond after `ready`. The host stops
    // reading 0.3 s before the row's first sample; the E-STOP opens 40 %
    // into the row, while that sample still waits, and the host reads
    // again 0.5 s later.
    let start = head.now() + 0.001;
    let tau = first + 0.4 * (last - first) - 0.001;
    head.deaf_between(start + first - 0.3, start + tau + 0.5);
    let s = trial(&mut head, Activity::SweepScan, Trigger::EStop, tau);
    assert!(s.laser_was_on, "the laser was off");
    assert!(s.laser_off_ms < 1.0, "dark after {} ms", s.laser_off_ms);
    assert_eq!(s.position_error_steps, 0);
    assert!(s.homed, "unhomed");
    assert_eq!(s.status.last_fault, Some(Fault::EmergencyStop));
}

/// Every stop in the middle of a sweep scan's row (the arm sweeping, the
/// chop running, between two of the serve loop's turns or within one)
/// darkens the laser at once and brakes the arm from its speed without
/// losing a step; continuing sweeps the row again from its start, whole.
#[test]
fn a_stop_mid_row_darkens_the_laser_brakes_the_arm_and_the_row_is_swept_again() {
    let mut head = FrameHead::new(&SimConfig::default());
    // When each row is swept, from an undisturbed run: the trials stop it
    // 40 % into a row's samples (the trial's clock starts a millisecond
    // after `ready`).
    let (whole, rows) = swept_rows(&mut head);
    assert_eq!(rows.len(), 2);
    let taus: Vec<f64> = rows.iter().map(|(a, b)| a + 0.4 * (b - a) - 0.001).collect();
    for trigger in Trigger::ALL {
        for &tau in &taus {
            ready(&mut head);
            let s = trial(&mut head, Activity::SweepScan, trigger, tau);
            let what = format!("{} at {tau:.2} s of {whole:.2} s", trigger.name());
            assert!(s.laser_was_on, "{what}: the laser was off");
            assert!(s.laser_off_ms < 1.0, "{what}: dark after {} ms", s.laser_off_ms);
            assert!(s.phases.iter().any(|(axis, _)| *axis == 2), "{what}: the arm was not moving");
            assert_eq!(s.position_error_steps, 0, "{what}");
            assert!(s.homed, "{what}: unhomed");
            assert!(s.stop_s <= decel_s_max() + 0.01, "{what}: stopped after {} s", s.stop_s);
            assert!(s.speed_jump <= 1.05, "{what}: speed jump {}", s.speed_jump);
            assert!(!s.status.laser_on, "{what}");
        }
    }
    // Paused mid-row and continued: the row is swept again, and every row
    // ends whole (as many samples as its `Swept` says, consecutive); the
    // retro point is measured once.
    ready(&mut head);
    let t = head.now();
    let scan = scan_frames(&small_sweep_scan()).into_iter().map(|f| (t, Cue::Frame(f)));
    let sent = head.serve_timed(
        scan.chain([
            (t + 0.35 * whole, Cue::Frame(send::<PauseEndpoint>(&()))),
            (t + 0.35 * whole + 2.0, Cue::Frame(send::<ContinueEndpoint>(&()))),
        ]),
        t + 3.0 * whole + 10.0,
    );
    let events = scan_events(&sent);
    assert!(
        matches!(
            events.last(),
            Some((
                ScanEvent::Finished {
                    measured: 3,
                    skipped: 0,
                    ..
                },
                _
            ))
        ),
        "{:?}",
        events.last()
    );
    let mut run: Vec<u32> = Vec::new();
    let mut rows = Vec::new();
    for (e, _) in &events {
        match e {
            ScanEvent::SweptSample(s) => {
                if run.last().is_some_and(|l| l + 1 != s.seq) {
                    run.clear();
                }
                run.push(s.seq);
            }
            ScanEvent::Swept { order, samples, .. } => {
                assert_eq!(run.len(), *samples as usize, "row {order}");
                rows.push(*order);
                run.clear();
            }
            ScanEvent::Paused { .. } => run.clear(),
            _ => {}
        }
    }
    // (Position 0 is the retro point, measured at rest.)
    assert_eq!(rows, [1, 2]);
}

fn far_move() -> Geometry {
    Geometry::new(60.0, 60.0, 180.0)
}

#[test]
fn an_abort_mid_move_brakes_from_the_current_speed_and_the_head_stays_homed() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let tau = 0.5 * gonio_tests::stopping::duration_s(&mut head, Activity::Move(far_move()));
    ready(&mut head);
    let back = Geometry::new(5.0, 5.0, 0.0);
    let s = trial(&mut head, Activity::Move(back), Trigger::Abort, tau.min(1.5));
    assert_eq!(replies::<MoveEndpoint>(&s.sent).first(), Some(&Err(Fault::Aborted)));
    assert!(!s.phases.is_empty(), "the trigger came mid-move");
    assert_eq!(s.position_error_steps, 0);
    assert!(s.homed, "the abort left the axes un-homed");
    assert!(s.stop_s > 0.0 && s.stop_s <= decel_s_max() + 0.01, "stopped after {} s", s.stop_s);
    assert!(s.speed_jump <= 1.05, "speed jump {}", s.speed_jump);
    assert_eq!(s.status.state, HeadState::Idle);
    assert!(!s.status.laser_on && !s.status.drivers_enabled);
    // The next move needs no homing, and ends where it should.
    ready(&mut head);
    let t = head.now();
    let sent = head.serve_timed([(t, Cue::Frame(send::<MoveEndpoint>(&back)))], t + 60.0);
    let moved = replies::<MoveEndpoint>(&sent);
    assert!(matches!(moved.first(), Some(Ok(_))), "{moved:?}");
}

#[test]
fn the_estop_darkens_a_measurement_at_once_and_rearms_only_once_closed() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let t = head.now();
    head.serve_timed([(t, Cue::Frame(send::<MoveEndpoint>(&Geometry::new(30.0, 30.0, 180.0))))], t + 60.0);
    let s = trial(&mut head, Activity::Measurement, Trigger::EStop, 0.04);
    assert!(
        s.laser_was_on && s.laser_off_ms <= 1.0,
        "laser dark after {} ms: {:?}",
        s.laser_off_ms,
        replies::<MeasureEndpoint>(&s.sent)
    );
    assert_eq!(replies::<MeasureEndpoint>(&s.sent).first(), Some(&Err(Fault::EmergencyStop)));
    assert_eq!(s.status.state, HeadState::Faulted);
    assert!(s.status.estop_open && s.status.homed);
    // Refused while faulted; continue refused while the input is open.
    head.world_mut().estop = true;
    let t = head.now();
    let sent = head.serve_timed(
        [
            (t, Cue::Frame(send::<MoveEndpoint>(&Geometry::new(20.0, 20.0, 180.0)))),
            (t + 0.01, Cue::Frame(send::<ContinueEndpoint>(&()))),
        ],
        t + 0.1,
    );
    assert_eq!(replies::<MoveEndpoint>(&sent), vec![Err(Fault::EmergencyStop)]);
    assert!(matches!(replies::<ContinueEndpoint>(&sent).as_slice(), [Err(Fault::EmergencyStop)]));
    assert!(!head.world().laser && head.world().enable_n.iter().all(|&off| off));
    // Closed again: continue re-arms after the debounce, and moves work.
    head.world_mut().estop = false;
    let t = head.now();
    let sent = head.serve_timed(
        [
            (t, Cue::Frame(send::<ContinueEndpoint>(&()))),
            (t + 0.1, Cue::Frame(send::<MoveEndpoint>(&Geometry::new(20.0, 20.0, 180.0)))),
        ],
        t + 60.0,
    );
    let st = replies::<ContinueEndpoint>(&sent);
    assert!(
        matches!(st.as_slice(), [Ok(s)] if s.state == HeadState::Idle && !s.estop_open),
        "{st:?}"
    );
    assert!(matches!(replies::<MoveEndpoint>(&sent).as_slice(), [Ok(_)]));
}

#[test]
fn the_drivers_let_go_after_the_idle_time_and_are_enabled_again_by_the_next_move() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let t = head.now();
    let sent = head.serve_timed(
        [
            (
                t,
                Cue::Frame(send::<SafetyEndpoint>(&SafetySettings {
                    idle_drivers_s: 30.0,
                    ..SafetySettings::default()
                })),
            ),
            (t + 0.001, Cue::Frame(send::<MoveEndpoint>(&Geometry::new(30.0, 30.0, 180.0)))),
        ],
        t + 60.0,
    );
    let moved = sent.iter().find(|s| s.frame.len() > 20).map(|s| s.t_s).unwrap();
    let status_at = |head: &mut FrameHead, at: f64| {
        let sent = head.serve_timed([(at, Cue::Frame(send::<StatusEndpoint>(&())))], at + 0.001);
        *replies::<StatusEndpoint>(&sent).last().unwrap()
    };
    // The link was open at rest in between: nothing but time passes.
    let mut head2 = FrameHead::new(&SimConfig::default());
    ready(&mut head2);
    let t2 = head2.now();
    let cues = [
        (
            t2,
            Cue::Frame(send::<SafetyEndpoint>(&SafetySettings {
                idle_drivers_s: 30.0,
                ..SafetySettings::default()
            })),
        ),
        (t2 + 0.001, Cue::Frame(send::<MoveEndpoint>(&Geometry::new(30.0, 30.0, 180.0)))),
        (t2 + (moved - t) + 20.0, Cue::Frame(send::<StatusEndpoint>(&()))),
        (t2 + (moved - t) + 40.0, Cue::Frame(send::<StatusEndpoint>(&()))),
    ];
    let sent = head2.serve_timed(cues, t2 + (moved - t) + 41.0);
    let st = replies::<StatusEndpoint>(&sent);
    assert!(st[0].drivers_enabled, "drivers let go before the idle time");
    assert!(
        !st[1].drivers_enabled && st[1].homed && st[1].state == HeadState::Idle,
        "{:?}",
        st[1]
    );
    drop(head);
    let at = head2.now();
    let s = status_at(&mut head2, at);
    assert!(!s.drivers_enabled);
    let t = head2.now();
    let sent = head2.serve_timed([(t, Cue::Frame(send::<MoveEndpoint>(&Geometry::new(40.0, 40.0, 180.0))))], t + 60.0);
    assert!(matches!(replies::<MoveEndpoint>(&sent).as_slice(), [Ok(_)]));
    assert!(sent.last().unwrap().drivers_enabled, "the move enabled the drivers");
}

#[test]
fn a_paused_scan_continues_where_it_stopped_and_measures_every_point_once() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let t = head.now();
    let mon = Geometry::new(10.0, 10.0, 180.0);
    let scan = scan_frames(&small_scan()).into_iter().map(|f| (t, Cue::Frame(f)));
    let sent = head.serve_timed(
        scan.chain([
            (t + 3.3, Cue::Frame(send::<PauseEndpoint>(&()))),
            // A monitor visit while the scan is held.
            (t + 4.0, Cue::Frame(send::<MeasureEndpoint>(&MeasureRequest { at: Some(mon) }))),
            (t + 9.0, Cue::Frame(send::<StatusEndpoint>(&()))),
            (t + 9.1, Cue::Frame(send::<ContinueEndpoint>(&()))),
        ]),
        t + 200.0,
    );
    let paused = replies::<PauseEndpoint>(&sent);
    assert!(
        matches!(paused.as_slice(), [Ok(s)] if matches!(s.state, HeadState::Paused { .. })),
        "{paused:?}"
    );
    assert!(matches!(replies::<MeasureEndpoint>(&sent).as_slice(), [Ok(_)]));
    let events = scan_events(&sent);
    let held = events.iter().position(|(e, _)| matches!(e, ScanEvent::Paused { reason: None, .. }));
    assert!(held.is_some(), "no Paused event");
    assert!(matches!(events.last(), Some((ScanEvent::Finished { .. }, _))));
    let mut seen = std::collections::BTreeSet::new();
    for (e, _) in &events {
        let index = match e {
            ScanEvent::Sample(s) => s.scan.map(|p| p.index),
            ScanEvent::Skipped { index, .. } => Some(*index),
            _ => None,
        };
        if let Some(i) = index {
            assert!(seen.insert(i), "point {i} visited twice");
        }
    }
    assert_eq!(seen.len() as u32, small_scan().len(), "every point once");
}

/// The serve loop shows it is alive at least every 250 ms of head time —
/// homing, a scan with long moves, a pause with a move, a minute at rest —
/// or, braking a move to a stop (which nothing may interrupt), within the
/// longest stop (0.5 s on the reference axes); the chip's watchdog, fed only
/// while the last sign is under 750 ms old, bites only when the loop is stuck.
/// And no move runs with the ADC converting.
#[test]
fn the_serve_loop_shows_it_is_alive_every_quarter_second() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let t = head.now();
    let scan = scan_frames(&small_scan()).into_iter().map(|f| (t, Cue::Frame(f)));
    let sent = head.serve_timed(
        scan.chain([
            (t + 3.3, Cue::Frame(send::<PauseEndpoint>(&()))),
            (t + 4.0, Cue::Frame(send::<MoveEndpoint>(&far_move()))),
            (t + 30.0, Cue::Frame(send::<ContinueEndpoint>(&()))),
            (t + 200.0, Cue::Frame(send::<StatusEndpoint>(&()))),
        ]),
        t + 260.0,
    );
    assert!(matches!(scan_events(&sent).last(), Some((ScanEvent::Finished { .. }, _))));
    let w = head.world();
    assert!(w.t_s > t + 250.0, "the head rested a minute after the scan");
    // No move ran with the conversions on (on the chip the ADC's ring would
    // overrun during it and lose its alignment with the chop).
    assert_eq!(w.moves_with_conversions, 0);
    let stop_s = REFERENCE
        .axes
        .iter()
        .map(|a| (a.max_speed_dps / a.max_accel_dps2) as f64)
        .fold(0.0, f64::max);
    let gap = w.alive_gap_max_s;
    assert!(gap > 0.2 && gap <= stop_s + 0.01, "longest time without a sign of life: {gap} s");
}

/// A move's first step waits for the chip to have planned it: the simulated
/// head charges what `chip-bench` measures per block (the duration estimate
/// counts the same), so it cannot hide a cost the chip pays.
#[test]
fn a_move_starts_once_the_chip_has_planned_it() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let before = head.world().steps;
    let t = head.now();
    head.world_mut().step_log = Some(Vec::new());
    let sent = head.serve_timed([(t, Cue::Frame(send::<MoveEndpoint>(&far_move())))], t + 60.0);
    assert!(matches!(replies::<MoveEndpoint>(&sent).first(), Some(Ok(_))));
    let steps = head.world_mut().step_log.take().unwrap_or_default();
    let first = steps.iter().map(|(_, at)| *at).fold(f64::INFINITY, f64::min);
    let delta = [0, 1, 2].map(|i| head.world().steps[i] - before[i]);
    let planning = blocks::plan_s(motion::move_blocks(&REFERENCE, delta, 1_000_000));
    assert!(planning > 5e-4, "{planning} s to plan a long move");
    // The first step of the profile itself, on the axis that steps first.
    let profile = (0..3)
        .filter(|&i| delta[i] != 0)
        .map(|i| motion::trapezoid(&REFERENCE.axes[i], delta[i].unsigned_abs(), REFERENCE.axes[i].max_speed_dps).step_time(1))
        .fold(f64::INFINITY, f64::min);
    let lag = first - t - profile;
    // Planning, then the driver's DIR setup time (5 µs) and the timer's tick.
    assert!(
        lag >= planning && lag <= planning + 1e-4,
        "the first step comes {lag} s late; planning takes {planning} s"
    );
}

/// `safety-bench`'s bars, on a few trials of every trigger and activity
/// (the binary runs 1 000 per trigger).
#[test]
fn the_safety_bench_bars_hold_on_a_sample_of_its_trials() {
    let out = gonio_tests::safety_trials::run(25);
    assert_eq!(out["all_bars_met"], true, "{out:#}");
}

/// A drift-monitor visit moves while a scan is held: an abort in the middle
/// of that move brakes it like any other, the drivers let go only once the
/// stages stand, and no step is lost.
#[test]
fn an_abort_during_a_move_in_a_pause_brakes_before_the_drivers_let_go() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let (st, _) = gonio_tests::stopping::status(&mut head);
    let before = gonio_tests::stopping::offset(&head, &st);
    let t = head.now();
    let scan = scan_frames(&small_scan()).into_iter().map(|f| (t, Cue::Frame(f)));
    let sent = head.serve_timed(
        scan.chain([
            (t + 3.3, Cue::Frame(send::<PauseEndpoint>(&()))),
            (t + 5.0, Cue::Frame(send::<MoveEndpoint>(&far_move()))),
            (t + 6.0, Cue::Frame(send::<gonio_shared::icd::AbortEndpoint>(&()))),
        ]),
        t + 10.0,
    );
    assert!(matches!(replies::<PauseEndpoint>(&sent).as_slice(), [Ok(_)]));
    assert_eq!(replies::<MoveEndpoint>(&sent), vec![Err(Fault::Aborted)]);
    let (st, _) = gonio_tests::stopping::status(&mut head);
    assert_eq!(gonio_tests::stopping::offset(&head, &st), before, "a step lost in the stop");
    assert_eq!(st.state, HeadState::Idle);
    assert!(st.homed && !st.drivers_enabled && !st.laser_on);
    assert!(matches!(
        scan_events(&sent).last(),
        Some((
            ScanEvent::Stopped {
                reason: Fault::Aborted,
                ..
            },
            _
        ))
    ));
}

#[test]
fn the_laser_stays_on_for_its_idle_time_after_a_measurement_then_goes_off() {
    let mut head = FrameHead::new(&SimConfig::default());
    ready(&mut head);
    let t = head.now();
    let safety = SafetySettings {
        laser_idle_s: 5.0,
        ..SafetySettings::default()
    };
    let sent = head.serve_timed(
        [
            (t, Cue::Frame(send::<SafetyEndpoint>(&safety))),
            (t + 0.001, Cue::Frame(send::<MeasureEndpoint>(&MeasureRequest { at: None }))),
            (t + 2.0, Cue::Frame(send::<StatusEndpoint>(&()))),
            (t + 8.0, Cue::Frame(send::<StatusEndpoint>(&()))),
            // A move switches it off at once.
            (t + 8.1, Cue::Frame(send::<MeasureEndpoint>(&MeasureRequest { at: None }))),
            (t + 8.5, Cue::Frame(send::<MoveEndpoint>(&far_move()))),
        ],
        t + 30.0,
    );
    let st = replies::<StatusEndpoint>(&sent);
    assert!(st[0].laser_on, "the laser went off before its idle time");
    assert!(!st[1].laser_on, "the laser stayed on past its idle time");
    let moved = sent
        .iter()
        .rev()
        .find(|s| replies::<MoveEndpoint>(std::slice::from_ref(s)).len() == 1)
        .unwrap();
    assert!(!moved.laser, "the laser stayed on through a move");
}

/// Homing from where the stages power up takes minutes on the reference
/// head, and the host polls the status every few seconds to show it is
/// there, expecting an answer within 5 s: each poll is answered at once, as
/// homing, while homing goes on; the homing's own answer comes at its end.
#[test]
fn a_status_poll_during_homing_is_answered_at_once() {
    let mut head = FrameHead::new(&SimConfig::default());
    let home = HomeRequest {
        rotation: true,
        cradle: true,
        arm: true,
    };
    let polls = [5.0, 10.0, 15.0];
    let cues = std::iter::once((0.0, Cue::Frame(send::<HomeEndpoint>(&home))))
        .chain(polls.iter().map(|&t| (t, Cue::Frame(send::<StatusEndpoint>(&())))));
    let sent = head.serve_timed(cues, 600.0);
    let statuses: Vec<(f64, gonio_shared::Status)> = sent
        .iter()
        .filter_map(|s| replies::<StatusEndpoint>(std::slice::from_ref(s)).pop().map(|st| (s.t_s, st)))
        .collect();
    let homed_at = sent
        .iter()
        .find(|s| !replies::<HomeEndpoint>(std::slice::from_ref(s)).is_empty())
        .map(|s| s.t_s)
        .expect("homing answered");
    assert!(
        homed_at > polls[polls.len() - 1] + 1.0,
        "homing took {homed_at} s: too short to poll during it"
    );
    assert_eq!(statuses.len(), polls.len(), "{statuses:?}");
    for ((t, status), asked) in statuses.iter().zip(polls) {
        assert!(t - asked < 0.01, "the poll at {asked} s was answered at {t} s");
        assert_eq!(status.state, HeadState::Homing, "at {t} s");
        assert!(
            (status.uptime_us as f64 * 1e-6 - t).abs() < 0.01,
            "uptime {} µs at {t} s",
            status.uptime_us
        );
    }
}
