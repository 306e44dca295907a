//! Stops measured on the simulated head: a trigger (abort, a
//! pulled cable, a silent host, the E-STOP) at a chosen moment of simulated
//! time in the middle of an activity, and what the virtual hardware saw:
//! when the laser went dark, when the last step fell, how the step
//! intervals changed on the way down, and whether the firmware's position
//! still matches the motors'. Shared by `safety-bench` and the tests.

use gonio_firmware::config::{AxisConfig, REFERENCE};
use gonio_firmware::motion;
use gonio_frames::{replies, scan_events, scan_frames, send};
use gonio_shared::icd::{
    AbortEndpoint, ContinueEndpoint, DetectionEndpoint, HomeEndpoint, HomeRequest, MeasureEndpoint, MeasureRequest, MoveEndpoint,
    SafetyEndpoint, StatusEndpoint,
};
use gonio_shared::{DetectionSettings, Geometry, SafetySettings, ScanEvent, ScanSpec, Status};
use gonio_sim::{Cue, FrameHead, Sent};

/// Largest change of step interval between two consecutive steps, relative
/// to the change a ramp at the acceleration limit `a` (steps/s²) makes at
/// the same speed: 1 on such a ramp, above 1 for a jump in speed. Speeding
/// up is compared with the ramp up, slowing down with the ramp down; a step
/// slower than a ramp's first (or last) one has nothing to compare with.
/// `times` are the steps of one axis (s), in order.
pub fn speed_jump(times: &[f64], a: f64) -> f64 {
    let c = (2.0 / a).sqrt();
    let mut worst = 1.0f64;
    for w in times.windows(3) {
        let (i1, i2) = (w[1] - w[0], w[2] - w[1]);
        if i1 <= 0.0 || i2 <= 0.0 {
            continue;
        }
        let s = c / i1;
        if s <= 1.0 {
            continue;
        }
        // Steps from rest (or to the stop) of a ramp stepping at this interval.
        let k = ((s + 1.0 / s) / 2.0).powi(2);
        let rho = i2 / i1;
        let jump = if rho >= 1.0 {
            if k < 2.0 {
                continue;
            }
            let ramp = (k.sqrt() + (k - 1.0).sqrt()) / ((k - 1.0).sqrt() + (k - 2.0).max(0.0).sqrt());
            rho / ramp
        } else {
            let ramp = (k.sqrt() + (k - 1.0).sqrt()) / ((k + 1.0).sqrt() + k.sqrt());
            ramp / rho
        };
        worst = worst.max(jump);
    }
    worst
}

/// Acceleration limit of an axis in microsteps/s².
pub fn accel_steps(a: &AxisConfig) -> f64 {
    a.max_accel_dps2 as f64 * a.microsteps_per_rev as f64 / 360.0
}

/// The longest deceleration of any axis from its maximum speed (s).
pub fn decel_s_max() -> f64 {
    REFERENCE
        .axes
        .iter()
        .map(|a| a.max_speed_dps as f64 / a.max_accel_dps2 as f64)
        .fold(0.0, f64::max)
}

/// What stops the head.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trigger {
    Abort,
    LinkLoss,
    HostSilence,
    EStop,
}

impl Trigger {
    pub const ALL: [Trigger; 4] = [Trigger::Abort, Trigger::LinkLoss, Trigger::HostSilence, Trigger::EStop];

    pub fn name(self) -> &'static str {
        match self {
            Trigger::Abort => "abort",
            Trigger::LinkLoss => "link_loss",
            Trigger::HostSilence => "host_silence",
            Trigger::EStop => "estop",
        }
    }
}

/// What the head is doing when it is stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Activity {
    Move(Geometry),
    Homing,
    /// A measurement where the head stands (laser on).
    Measurement,
    Scan,
    /// A sweep scan (its rows swept by the arm, the laser on).
    SweepScan,
}

/// A sweep scan of two rows, for stops in the middle of a row.
pub fn small_sweep_scan() -> ScanSpec {
    ScanSpec {
        dphi: gonio_shared::AngleRange::new(-30.0, 30.0, 60.0),
        theta_o: gonio_shared::AngleRange::new(0.0, 80.0, 1.0),
        sweep: Some(gonio_shared::SweepScan {
            speed_dps: 10.0,
            periods_per_sample: 8,
            lobe: None,
        }),
        ..small_scan()
    }
}

/// An undisturbed run of [`small_sweep_scan`] on a ready head: how long it
/// took and each row's first and last swept sample, in visit order (s from
/// the scan's start; the retro point, measured at rest, is no row).
pub fn swept_rows(head: &mut FrameHead) -> (f64, Vec<(f64, f64)>) {
    ready(head);
    let t0 = head.now();
    let sent = head.serve_timed(
        scan_frames(&small_sweep_scan()).into_iter().map(|f| (t0, Cue::Frame(f))),
        t0 + 600.0,
    );
    let events = scan_events(&sent);
    let whole = events.last().map(|(_, s)| s.t_s - t0).expect("the scan ended");
    let mut rows: std::collections::BTreeMap<u32, (f64, f64)> = Default::default();
    for (e, sent) in &events {
        if let ScanEvent::SweptSample(s) = e {
            let t = sent.t_s - t0;
            let row = rows.entry(s.scan.expect("a row's sample").order).or_insert((t, t));
            row.1 = t;
        }
    }
    (whole, rows.into_values().collect())
}

/// Where an axis's motion was when the trigger came.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    Acceleration,
    Cruise,
    Deceleration,
}

/// What one stop did.
#[derive(Debug, Clone)]
pub struct Stop {
    /// The laser was on when the trigger came...
    pub laser_was_on: bool,
    /// ...and dark this long after it (ms); 0 when it was dark already.
    pub laser_off_ms: f64,
    /// The last step this long after the trigger (s); 0 when none followed.
    pub stop_s: f64,
    /// Change, over the trial, of the firmware's position less the motors'
    /// true one, largest axis (microsteps): a step lost or counted twice.
    /// (The offset itself is homing's: the slow approach stops within its
    /// 4-microstep chunk of the switch.)
    pub position_error_steps: i64,
    /// [`speed_jump`] over the stop, worst axis.
    pub speed_jump: f64,
    /// Phase of each axis moving at the trigger.
    pub phases: Vec<(usize, Phase)>,
    /// The head is homed after the stop.
    pub homed: bool,
    /// The status read after the stop.
    pub status: Status,
    /// Frames the head sent during the trial.
    pub sent: Vec<Sent>,
}

/// A scan of 35 points near the specular direction, for scan trials.
pub fn small_scan() -> ScanSpec {
    ScanSpec {
        theta_o: gonio_shared::AngleRange::new(10.0, 70.0, 10.0),
        dphi: gonio_shared::AngleRange::new(-60.0, 60.0, 30.0),
        theta_i_deg: heapless::Vec::from_slice(&[30.0]).expect("one incidence"),
        first_order: 0,
        sweep: None,
        patterns: None,
    }
}

/// Where an axis was in its ramp at `t`, from its steps before it: the mean
/// interval of the last 8 steps against the 8 before (which averages out the
/// step timer's tick), shrinking (accelerating), steady, or growing.
fn phase_at(times: &[f64], t: f64) -> Option<Phase> {
    const W: usize = 8;
    let k = times.partition_point(|&x| x <= t);
    if k >= times.len() {
        return None;
    }
    if k < 2 * W + 1 {
        // Within the first steps of a move: speeding up from rest.
        return (k > 0).then_some(Phase::Acceleration);
    }
    let mean = |a: usize| (times[a + W] - times[a]) / W as f64;
    let r = mean(k - 1 - W) / mean(k - 1 - 2 * W);
    Some(if r < 0.995 {
        Phase::Acceleration
    } else if r > 1.005 {
        Phase::Deceleration
    } else {
        Phase::Cruise
    })
}

/// The requests that start an activity.
fn request(a: Activity) -> Vec<Vec<u8>> {
    match a {
        Activity::Move(g) => vec![send::<MoveEndpoint>(&g)],
        Activity::Homing => vec![send::<HomeEndpoint>(&HomeRequest::ALL)],
        Activity::Measurement => vec![send::<MeasureEndpoint>(&MeasureRequest { at: None })],
        Activity::Scan => scan_frames(&small_scan()),
        Activity::SweepScan => scan_frames(&small_sweep_scan()),
    }
}

/// The cues that start `activity` at `t0`: the detection settings (a
/// measurement integrates for 2 s, long enough for every trigger, the host
/// watch being at least 1 s, to fall inside it), the host watch, the request.
fn start(activity: Activity, t0: f64, host_timeout_s: f32) -> Vec<(f64, Cue)> {
    let d = DetectionSettings::default();
    let detection = match activity {
        Activity::Measurement => DetectionSettings {
            periods: d.periods_for(2.0),
            ..d
        },
        _ => d,
    };
    let safety = SafetySettings {
        host_timeout_s,
        ..SafetySettings::default()
    };
    let setup = [
        (t0 - 0.0008, Cue::Frame(send::<DetectionEndpoint>(&detection))),
        (t0 - 0.0005, Cue::Frame(send::<SafetyEndpoint>(&safety))),
    ];
    setup
        .into_iter()
        .chain(request(activity).into_iter().map(|f| (t0, Cue::Frame(f))))
        .collect()
}

/// How long an activity takes on this head from its request to its answer
/// (a scan: to its end), measured by running it once undisturbed, for
/// choosing moments inside it. A move ends where it went.
pub fn duration_s(head: &mut FrameHead, a: Activity) -> f64 {
    let t0 = head.now() + 0.001;
    let sent = head.serve_timed(start(a, t0, 0.0), t0 + 3600.0);
    let end = match a {
        Activity::Scan | Activity::SweepScan => scan_events(&sent)
            .iter()
            .find(|(e, _)| matches!(e, ScanEvent::Finished { .. }))
            .map(|(_, s)| s.t_s),
        // The third answer: after those to the settings.
        _ => sent.get(2).map(|s| s.t_s),
    };
    end.expect("the activity ended") - t0
}

/// Makes the head ready for a trial: E-STOP closed and re-armed, no scan
/// held, no host watch, homed.
pub fn ready(head: &mut FrameHead) {
    {
        let mut w = head.world_mut();
        w.estop = false;
        w.estop_at = None;
    }
    let t = head.now();
    let sent = head.serve_timed(
        [
            (t, Cue::Frame(send::<ContinueEndpoint>(&()))),
            (t + 0.05, Cue::Frame(send::<ContinueEndpoint>(&()))),
            // A scan held by the last stop is dropped.
            (t + 0.08, Cue::Frame(send::<AbortEndpoint>(&()))),
            // No host watch left from the last trial.
            (t + 0.09, Cue::Frame(send::<SafetyEndpoint>(&SafetySettings::default()))),
            (t + 0.1, Cue::Frame(send::<StatusEndpoint>(&()))),
        ],
        t + 0.2,
    );
    let homed = replies::<StatusEndpoint>(&sent).last().is_some_and(|s| s.homed);
    if !homed {
        let t = head.now();
        let r = replies::<HomeEndpoint>(&head.serve_timed([(t, Cue::Frame(send::<HomeEndpoint>(&HomeRequest::ALL)))], t + 900.0));
        assert!(matches!(r.last(), Some(Ok(_))), "homing before a trial: {r:?}");
    }
}

/// The head's status, read on a fresh link.
pub fn status(head: &mut FrameHead) -> (Status, Vec<Sent>) {
    let t = head.now();
    let sent = head.serve_timed([(t, Cue::Frame(send::<StatusEndpoint>(&())))], t + 0.01);
    (*replies::<StatusEndpoint>(&sent).last().expect("a status"), sent)
}

/// Where the firmware believes the axes are, less where they are (microsteps).
pub fn offset(head: &FrameHead, s: &Status) -> [i64; 3] {
    let fw = motion::target_steps(&REFERENCE, &s.axes);
    let w = head.world();
    [0, 1, 2].map(|i| fw[i] as i64 - w.steps[i] as i64)
}

/// Runs `activity` on a ready head and stops it by `trigger` `tau` seconds
/// after its request; reads the status after the stop.
pub fn trial(head: &mut FrameHead, activity: Activity, trigger: Trigger, tau: f64) -> Stop {
    let before = {
        let (s, _) = status(head);
        offset(head, &s)
    };
    let t0 = head.now() + 0.001;
    let tt = t0 + tau;
    {
        let mut w = head.world_mut();
        w.step_log = Some(Vec::new());
        w.laser_log = Some(Vec::new());
        if trigger == Trigger::EStop {
            w.estop_at = Some(tt);
            w.wake(tt);
        }
    }
    let host_timeout_s = if trigger == Trigger::HostSilence { tau as f32 } else { 0.0 };
    let mut cues = start(activity, t0, host_timeout_s);
    match trigger {
        Trigger::Abort => cues.push((tt, Cue::Frame(send::<AbortEndpoint>(&())))),
        Trigger::LinkLoss => cues.push((tt, Cue::Close)),
        Trigger::HostSilence | Trigger::EStop => {}
    }
    let mut sent = head.serve_timed(cues, tt + decel_s_max() + 0.5);
    let (status, after) = status(head);
    sent.extend(after);
    let moved = offset(head, &status);
    let position_error_steps = (0..3).map(|i| (moved[i] - before[i]).abs()).max().unwrap_or(0);
    let mut w = head.world_mut();
    let steps = w.step_log.take().unwrap_or_default();
    let laser = w.laser_log.take().unwrap_or_default();
    w.estop_at = None;
    // The head counts the host's silence in whole µs (the frame heard last
    // and its clock rounded, an f32 timeout rounded up): its watch runs out
    // within 2 µs of `tt` for the τ of under 32 s the trials draw, either
    // side (39 ns before it once a sweep scan began with its retro point).
    let before = if trigger == Trigger::HostSilence { tt - 2e-6 } else { tt };
    let was_on = laser.iter().rev().find(|(t, _)| *t < before).is_some_and(|(_, on)| *on);
    let laser_off_ms = if was_on {
        laser
            .iter()
            .find(|(t, on)| *t >= before && !on)
            .map_or(f64::INFINITY, |(t, _)| (t - tt) * 1e3)
    } else {
        0.0
    };
    let stop_s = steps.iter().filter(|(_, t)| *t > tt).map(|(_, t)| t - tt).fold(0.0, f64::max);
    let mut jump = 1.0f64;
    let mut phases = Vec::new();
    for (axis, cfg) in REFERENCE.axes.iter().enumerate() {
        let times: Vec<f64> = steps.iter().filter(|(a, _)| *a == axis).map(|(_, t)| *t).collect();
        if !times.iter().any(|&t| t > tt) {
            continue;
        }
        if let Some(p) = phase_at(&times, tt) {
            phases.push((axis, p));
        }
        // The stop and the few steps before it.
        let from = times.partition_point(|&t| t <= tt).saturating_sub(4);
        jump = jump.max(speed_jump(&times[from..], accel_steps(cfg)));
    }
    let homed = status.homed;
    drop(w);
    Stop {
        laser_was_on: was_on,
        laser_off_ms,
        stop_s,
        position_error_steps,
        speed_jump: jump,
        phases,
        homed,
        status,
        sent,
    }
}
