//! The head's half of the fault matrix (docs/faults.md): each
//! hardware fault, host silence and a pulled cable injected into the
//! simulated head, driven frame by frame. For each: the fault is reported
//! with its code, and when it is reported the laser is off and every motor
//! driver disabled (checked on the virtual pins at the moment the report
//! leaves). The host's half (recovery, no sample lost or duplicated,
//! resumption) is host/gonio/tests/fault_recovery.rs.

use gonio_frames::{replies, scan_events, scan_frames, send};
use gonio_shared::icd::{
    HomeEndpoint, HomeRequest, LearnEndpoint, MeasureEndpoint, MeasureRequest, MoveEndpoint, SafetyEndpoint, ScanEndpoint, StatusEndpoint,
};
use gonio_shared::{AngleRange, Axis, Fault, Geometry, LearnRequest, SafetySettings, SampleFlags, ScanEvent, ScanSpec};
use gonio_sim::faults::Faults;
use gonio_sim::{FrameHead, Sent, SimConfig};

/// Points of [`spec`] in the plate's shadow (θo = 24° and 36° at Δφ = 0°,
/// 6° from the laser): skipped, and planned first, before any move.
const SHADOWED: u32 = 2;
/// Points of [`spec`] measured.
const MEASURED: usize = 143 - SHADOWED as usize;

/// 143 points at θi = 30°.
fn scan_spec() -> ScanSpec {
    ScanSpec {
        theta_o: AngleRange::new(0.0, 60.0, 6.0),
        dphi: AngleRange::new(-180.0, 180.0, 30.0),
        theta_i_deg: heapless::Vec::from_slice(&[30.0]).unwrap(),
        first_order: 0,
        sweep: None,
        patterns: None,
    }
}

/// Homes and scans on a head suffering `faults`, the link open and silent.
fn scan(faults: &str, host_timeout_s: f32) -> (FrameHead, Vec<Sent>) {
    let cfg = SimConfig {
        faults: Faults::parse(faults).unwrap(),
        ..SimConfig::default()
    };
    let mut head = FrameHead::new(&cfg);
    // The watch is set after homing, as the host does (homing is long).
    let setup = [
        send::<HomeEndpoint>(&HomeRequest::ALL),
        send::<SafetyEndpoint>(&SafetySettings {
            host_timeout_s,
            ..SafetySettings::default()
        }),
    ];
    let sent = head.serve_open(setup.into_iter().chain(scan_frames(&scan_spec())));
    (head, sent)
}

/// The scan's stop (or hold, for host silence), checked to leave the head
/// safe, and the samples before it.
fn stopped(sent: &[Sent]) -> (Fault, u32, usize) {
    let events = scan_events(sent);
    let samples = events.iter().filter(|(e, _)| matches!(e, ScanEvent::Sample(_))).count();
    assert!(
        events
            .iter()
            .any(|(e, s)| matches!(e, ScanEvent::Sample(_)) && s.laser && s.drivers_enabled),
        "the laser was on and the drivers enabled while scanning"
    );
    let (ev, at) = events.last().expect("scan events");
    let (ScanEvent::Stopped { reason, next_order, .. }
    | ScanEvent::Paused {
        reason: Some(reason),
        next_order,
        ..
    }) = ev
    else {
        panic!("the scan was not stopped: {ev:?}");
    };
    assert!(!at.laser, "{reason}: laser still on when the fault was reported");
    assert!(!at.drivers_enabled, "{reason}: drivers still enabled when the fault was reported");
    (*reason, *next_order, samples)
}

fn finished(sent: &[Sent]) -> Vec<gonio_shared::Sample> {
    let events = scan_events(sent);
    let (last, at) = events.last().expect("scan events");
    assert!(
        matches!(
            last,
            ScanEvent::Finished {
                measured: 141,
                skipped: SHADOWED,
                ..
            }
        ),
        "{last:?}"
    );
    // The drivers hold the stages until the idle watch lets them go.
    assert!(!at.laser && at.drivers_enabled, "laser off, stages held at the end of the scan");
    events
        .into_iter()
        .filter_map(|(e, _)| match e {
            ScanEvent::Sample(s) => Some(s),
            _ => None,
        })
        .collect()
}

#[test]
fn a_clean_scan_finishes_in_the_safe_state() {
    let (_, sent) = scan("", 0.0);
    assert_eq!(finished(&sent).len(), MEASURED);
}

#[test]
fn home_switch_stuck_open_or_closed_is_reported_with_the_head_safe() {
    for (spec, want) in [
        ("switch-open@0:1", Fault::HomeSwitchNotFound(Axis::Cradle)),
        ("switch-closed@0:2", Fault::HomeSwitchStuck(Axis::Arm)),
    ] {
        let (head, sent) = scan(spec, 0.0);
        let home = replies::<HomeEndpoint>(&sent);
        assert_eq!(home, vec![Err(want)], "{spec}");
        // The scan is refused unhomed: nothing moves, the laser stays dark.
        assert_eq!(replies::<ScanEndpoint>(&sent), vec![Err(Fault::NotHomed)], "{spec}");
        let w = head.world();
        assert!(!w.laser && w.enable_n.iter().all(|&off| off), "{spec}: safe state");
        assert!(scan_events(&sent).is_empty(), "{spec}: no scan ran");
    }
}

#[test]
fn a_saturated_adc_stops_the_scan_after_a_run_of_saturated_points() {
    let (reason, next, samples) = stopped(&scan("saturated@30", 0.0).1);
    assert_eq!(reason, Fault::Saturated);
    // Points 30..37 saturate; the eighth stops the scan and is measured again on resume.
    assert_eq!(next, SHADOWED + 30 + gonio_firmware::active_scan::SUSPECT_STREAK - 1);
    assert_eq!(samples, (next - SHADOWED) as usize);
}

#[test]
fn a_dead_laser_stops_the_scan_after_a_run_of_dark_points() {
    let (reason, next, _) = stopped(&scan("laser-dead@30", 0.0).1);
    assert_eq!(reason, Fault::NoSignal);
    assert_eq!(next, SHADOWED + 30 + gonio_firmware::active_scan::SUSPECT_STREAK - 1);
}

#[test]
fn a_stalled_move_stops_the_scan() {
    let (reason, next, samples) = stopped(&scan("stall@30", 0.0).1);
    assert!(matches!(reason, Fault::StepTimer(_)), "{reason}");
    assert_eq!((next, samples), (SHADOWED + 30, 30));
}

#[test]
fn one_lost_adc_block_is_measured_again_and_a_lasting_overrun_stops_the_scan() {
    let samples = finished(&scan("overrun@30:1", 0.0).1);
    assert!(samples.iter().all(|s| !s.signal.flags.contains(SampleFlags::OVERRUN)));
    let (reason, next, _) = stopped(&scan("overrun@30:40", 0.0).1);
    assert_eq!((reason, next), (Fault::AdcOverrun, SHADOWED + 30));
}

/// The host sends nothing after starting the scan: with a 5 s watch the head
/// stops within the first few points and holds the scan there (a host that
/// comes back continues it); without one it scans to the end.
#[test]
fn host_silence_stops_the_scan_when_watched() {
    let (_, sent) = scan("", 5.0);
    let (reason, next, _) = stopped(&sent);
    assert!(matches!(scan_events(&sent).last(), Some((ScanEvent::Paused { .. }, _))));
    assert_eq!(reason, Fault::HostSilent);
    assert!((1..20).contains(&next), "stopped at {next}");
    assert_eq!(finished(&scan("", 0.0).1).len(), MEASURED);
}

/// The cable is pulled mid-scan: the head leaves the laser off and the
/// drivers disabled.
#[test]
fn a_pulled_cable_leaves_the_head_safe() {
    let mut head = FrameHead::new(&SimConfig::default());
    let home = send::<HomeEndpoint>(&HomeRequest::ALL);
    let sent = head.serve_cut(std::iter::once(home).chain(scan_frames(&scan_spec())), 40);
    let (last, at) = scan_events(&sent).pop().unwrap();
    assert!(matches!(last, ScanEvent::Sample(_)) && at.laser, "the cable was pulled mid-scan");
    let w = head.world();
    assert!(!w.laser && w.enable_n.iter().all(|&off| off));
}

/// A request damaged on the way (each single bit flipped in turn, and the
/// frame cut short) is dropped unanswered and does nothing; the host finds
/// it lost (its probe is answered first) and reconnects. The same request
/// undamaged moves the stages.
#[test]
fn a_damaged_request_is_dropped_unanswered_and_moves_nothing() {
    let mut head = FrameHead::new(&SimConfig::default());
    assert_eq!(
        replies::<HomeEndpoint>(&head.serve([send::<HomeEndpoint>(&HomeRequest::ALL)])).len(),
        1
    );
    let homed = head.world().steps;
    let good = send::<MoveEndpoint>(&Geometry::new(40.0, 30.0, 90.0));
    let mut damaged: Vec<Vec<u8>> = (0..good.len() * 8)
        .map(|bit| {
            let mut f = good.clone();
            f[bit / 8] ^= 1 << (bit % 8);
            f
        })
        .collect();
    damaged.extend((1..good.len()).map(|n| good[..n].to_vec()));
    let sent = head.serve(damaged);
    assert!(sent.is_empty(), "the head answered a damaged request: {} frames", sent.len());
    let w = head.world();
    assert_eq!(w.steps, homed, "a damaged request moved the stages");
    assert!(!w.laser && w.laser_ons == 0, "a damaged request switched the laser on");
    drop(w);
    assert_eq!(replies::<MoveEndpoint>(&head.serve([good])).len(), 1);
    assert_ne!(head.world().steps, homed, "the undamaged request moves the stages");
}

/// A head whose crystal failed its check at boot (12 MHz on an 8 MHz
/// board, or none) says so in its status and refuses everything that needs
/// the laser, before anything moves; it still homes and moves, for bring-up.
#[test]
fn a_head_on_its_internal_oscillator_keeps_its_laser_off() {
    for khz in [12_000, 0] {
        let cfg = SimConfig {
            faults: Faults::parse(&format!("crystal@0:{khz}")).unwrap(),
            ..SimConfig::default()
        };
        let crystal = Fault::Crystal {
            measured_khz: khz,
            expected_khz: 8_000,
        };
        let mut head = FrameHead::new(&cfg);
        let status = replies::<StatusEndpoint>(&head.serve([send::<StatusEndpoint>(&())]));
        assert_eq!(status[0].laser_inhibited, Some(crystal));
        assert_eq!(status[0].last_fault, None, "no restart to report");
        assert_eq!(
            replies::<HomeEndpoint>(&head.serve([send::<HomeEndpoint>(&HomeRequest::ALL)])).len(),
            1
        );
        let homed = head.world().steps;
        let at = Some(Geometry::new(40.0, 30.0, 90.0));
        let refused = [
            send::<MeasureEndpoint>(&MeasureRequest { at }),
            send::<LearnEndpoint>(&LearnRequest { periods: 64 }),
        ];
        let sent = head.serve(refused);
        assert_eq!(replies::<MeasureEndpoint>(&sent), vec![Err(crystal)]);
        assert_eq!(replies::<LearnEndpoint>(&sent), vec![Err(crystal)]);
        let scan = head.serve(scan_frames(&scan_spec()));
        assert_eq!(replies::<ScanEndpoint>(&scan), vec![Err(crystal)]);
        let w = head.world();
        assert_eq!(w.steps, homed, "a refused measurement moved the stages");
        assert_eq!(w.laser_ons, 0, "the laser came on");
        drop(w);
        assert_eq!(
            replies::<MoveEndpoint>(&head.serve([send::<MoveEndpoint>(&Geometry::new(40.0, 30.0, 90.0))])).len(),
            1
        );
        assert_ne!(head.world().steps, homed, "the axes still move");
    }
}

/// Safety settings are validated like every command.
#[test]
fn invalid_host_timeouts_are_refused() {
    let mut head = FrameHead::new(&SimConfig::default());
    let frames: Vec<_> = [f32::NAN, f32::INFINITY, -1.0, 0.5, 4000.0, 20.0]
        .map(|t| {
            send::<SafetyEndpoint>(&SafetySettings {
                host_timeout_s: t,
                ..SafetySettings::default()
            })
        })
        .into();
    let r = replies::<SafetyEndpoint>(&head.serve(frames));
    let bad = Err(Fault::InvalidValue(gonio_shared::Field::HostTimeout));
    assert_eq!(r, vec![bad, bad, bad, bad, bad, Ok(())]);
}
