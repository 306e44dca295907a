//! Host ↔ simulated head through the whole stack: postcard-rpc client, frames
//! on a link, the firmware's dispatcher, motion, auto-range and demodulation,
//! and the virtual photodiode.

use gonio::cli::in_process::Simulated;
use gonio_acquire::client::HeadClient;
use gonio_acquire::scan;
use gonio_acquire::scan_order::{dwell_s, scan_time, time_left_s, visit_order};
use gonio_acquire::target::{Port, Target};
use gonio_brdf::{Directions, Material, Specimen};
use gonio_firmware::config::REFERENCE;
use gonio_firmware::kinematics;
use gonio_firmware::motion::PARK;
use gonio_shared::icd::{
    AbortEndpoint, DetectionEndpoint, HomeEndpoint, HomeRequest, MeasureEndpoint, MeasureRequest, MoveEndpoint, StatusEndpoint,
};
use gonio_shared::{AngleRange, DetectionSettings, Geometry, HeadState, Reference, SampleFlags, ScanEvent, ScanSpec, PROTOCOL_VERSION};
use gonio_sim::{serve_pty, SimConfig};
use gonio_tests::scanning::{scan_and_read, session};
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Duration;

fn small_grid() -> ScanSpec {
    ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[30.0, 60.0]).unwrap(),
        theta_o: AngleRange::new(0.0, 87.0, 3.0),
        dphi: AngleRange::new(0.0, 180.0, 90.0),
        first_order: 0,
        sweep: None,
        patterns: None,
    }
}

async fn homed(target: &dyn Target) -> HeadClient {
    let head = HeadClient::connect(target).await.unwrap();
    head.request::<DetectionEndpoint>(&DetectionSettings::default()).await.unwrap();
    head.request::<HomeEndpoint>(&HomeRequest::ALL).await.unwrap();
    head
}

#[tokio::test]
async fn a_scan_stores_one_calibratable_sample_per_reachable_point() {
    // The retroreflective tape: its four decades need more than one gain.
    let sim = SimConfig {
        material: Specimen::Model(Material::tape()),
        ..SimConfig::default()
    };
    let mut session = session(Arc::new(Simulated(sim.clone()))).await;
    let dir = tempfile::tempdir().unwrap();
    let spec = small_grid();
    let (outcome, rows) = scan_and_read(&mut session, &spec, dir.path()).await;
    session.close().await;

    assert_eq!(outcome.points, spec.len());
    assert_eq!(outcome.measured + outcome.skipped, spec.len());
    assert_eq!(rows.len() as u32, outcome.measured);
    let measured: BTreeSet<u32> = rows.iter().map(|r| r.index.unwrap()).collect();
    assert_eq!(measured.len(), rows.len(), "a point was measured twice");
    let reachable: BTreeSet<u32> = (0..spec.len())
        .filter(|&i| kinematics::inverse(&REFERENCE, &spec.point(i).unwrap()).is_ok())
        .collect();
    assert_eq!(measured, reachable);

    // Photocurrent / (f_r · cosθo) is one instrument constant over the whole
    // scan, once the beam splitter's factor is divided out of the retro
    // zone's points, f_r as the detector's field sees it (on the tape's
    // retro peak 15 % below the value at the nominal view).
    let m = &sim.material;
    let field = sim.machine.optics.detector_sr as f64;
    let ratios: Vec<f64> = rows
        .iter()
        .map(|r| {
            assert!((r.theta_o_deg - r.target_theta_o_deg).abs() < 0.01 && (r.theta_i_deg - r.target_theta_i_deg).abs() < 0.01);
            let d = Directions::from_degrees(r.target_theta_i_deg as f64, r.target_theta_o_deg as f64, r.target_dphi_deg as f64);
            let splitter = if r.sample_flags().contains(SampleFlags::THROUGH_SPLITTER) {
                sim.photodiode.splitter_factor
            } else {
                1.0
            };
            assert!(!r.sample_flags().doubtful(), "unexpected flags on {r:?}");
            r.amplitude_v as f64 / r.gain_v_per_a as f64 / (gonio_sim::seen_brdf(m, field, &d) * d.cos_o() * splitter)
        })
        .collect();
    let mut sorted = ratios.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    for (r, k) in rows.iter().zip(&ratios) {
        // Within 2 % (the amplifier's lag differs slightly between gains)
        // plus five standard errors of the sample's own noise: the noise is
        // estimated from 23 periods, so the deviation over it is Student's
        // t with 22 degrees of freedom, beyond 4 once in 1 700 (at the
        // grazing points, where noise dominates, 180 points made that a
        // one-in-ten failure) and beyond 5 once in 20 000.
        let tol = 0.02 + 5.0 * (r.noise_v / r.amplitude_v) as f64;
        assert!(
            (k / median - 1.0).abs() < tol,
            "point {:?} off the instrument constant by {:.3} (tolerance {tol:.3})",
            r.index,
            k / median - 1.0
        );
    }
    // Four decades: the retro peak needs a lower gain than the diffuse floor.
    let gains: BTreeSet<u8> = rows.iter().map(|r| r.gain_index).collect();
    assert!(gains.len() >= 2, "gains used: {gains:?}");
}

/// The host plans and estimates a scan for the machine it talks to: on a
/// head whose arm is slower and whose rotation stage is geared otherwise, it
/// learns the mechanics from the head, visits in the order planned for them,
/// and its estimate is the head time to 1 % (189.47 s for 189.50 s); the
/// reference head's estimate is 30 % short, and its order another.
#[tokio::test]
async fn the_host_plans_for_the_mechanics_the_head_reports() {
    let mut machine = REFERENCE;
    machine.axes[2].max_speed_dps = 12.0;
    machine.axes[2].max_accel_dps2 = 18.0;
    machine.axes[0].microsteps_per_rev = 200 * 16 * 45;
    let sim = SimConfig {
        machine,
        ..SimConfig::default()
    };
    let mut session = session(Arc::new(Simulated(sim))).await;
    let cfg = *session.head().config();
    assert_eq!(cfg.mechanics(), machine.mechanics());
    let det = session.detection.unwrap();
    let dir = tempfile::tempdir().unwrap();
    let spec = small_grid();
    let (outcome, rows) = scan_and_read(&mut session, &spec, dir.path()).await;
    session.close().await;

    let mut visited: Vec<(u32, u32)> = rows.iter().filter_map(|r| Some((r.order?, r.index?))).collect();
    visited.sort();
    let reachable = |i: &u32| kinematics::inverse(&cfg, &spec.point(*i).unwrap()).is_ok();
    let planned: Vec<u32> = visit_order(&cfg, &spec, PARK).filter(reachable).collect();
    let for_reference: Vec<u32> = visit_order(&REFERENCE, &spec, PARK).filter(reachable).collect();
    assert_eq!(visited.iter().map(|v| v.1).collect::<Vec<_>>(), planned);

    let (settle, acquire) = dwell_s(&det);
    let estimate =
        |c: &gonio_firmware::config::HeadConfig| scan_time(c, &spec, visit_order(c, &spec, PARK), PARK, settle, acquire).total_s();
    let (ours, reference) = (estimate(&cfg), estimate(&REFERENCE));
    let head = outcome.head_time_s;
    assert!((ours - head).abs() < 0.01 * head, "estimate {ours} s, head time {head} s");
    assert!(
        (reference - head).abs() > 0.2 * head,
        "reference estimate {reference} s, head time {head} s"
    );
    assert_ne!(planned, for_reference, "the test needs a head the reference plan does not fit");
    // The progress bar's time left: the same plan, position by position,
    // from the whole estimate down to nothing.
    let left = time_left_s(&cfg, &spec, visit_order(&cfg, &spec, PARK), PARK, &det);
    assert_eq!(left.len(), spec.len() as usize + 1);
    assert!((left[0] - ours).abs() < 1e-9 * ours, "{} vs {ours}", left[0]);
    assert!(left.windows(2).all(|w| w[1] <= w[0]) && *left.last().unwrap() == 0.0);
}

#[tokio::test]
async fn a_protocol_version_mismatch_is_named() {
    let sim = SimConfig {
        protocol_version: PROTOCOL_VERSION + 1,
        ..SimConfig::default()
    };
    let err = HeadClient::connect(&Simulated(sim)).await.err().expect("connecting must fail");
    let msg = format!("{err:#}");
    assert!(msg.contains("protocol version mismatch"), "{msg}");
    assert!(msg.contains(&format!("v{}", PROTOCOL_VERSION + 1)), "{msg}");
}

#[tokio::test]
async fn refused_commands_move_nothing() {
    let head = HeadClient::connect(&Simulated::default()).await.unwrap();
    let err = head
        .request::<MeasureEndpoint>(&MeasureRequest {
            at: Some(Geometry::new(30.0, 30.0, 0.0)),
        })
        .await
        .unwrap_err();
    assert!(format!("{err:#}").contains("not homed"), "{err:#}");
    let matched = DetectionSettings {
        reference: Reference::Matched,
        ..DetectionSettings::default()
    };
    let err = head.request::<DetectionEndpoint>(&matched).await.unwrap_err();
    assert!(format!("{err:#}").contains("not learned"), "{err:#}");
    head.request::<HomeEndpoint>(&HomeRequest::ALL).await.unwrap();
    let before = head.request::<StatusEndpoint>(&()).await.unwrap();
    for (g, why) in [
        (Geometry::new(30.0, 38.0, 0.0), "blind zone"),
        (Geometry::new(30.0, 95.0, 0.0), "behind the sample"),
        (Geometry::new(f32::NAN, 10.0, 0.0), "invalid theta_i"),
        (Geometry::new(87.0, 87.0, 180.0), "travel of the arm"),
    ] {
        let err = head.request::<MoveEndpoint>(&g).await.unwrap_err();
        assert!(format!("{err:#}").contains(why), "{g:?}: {err:#}");
    }
    let after = head.request::<StatusEndpoint>(&()).await.unwrap();
    assert_eq!(before.axes, after.axes);
    assert!(!after.laser_on);
    head.close().await;
}

#[tokio::test]
async fn an_aborted_scan_stops_darkens_the_laser_and_resumes_where_it_stopped() {
    let head = homed(&Simulated::default()).await;
    let spec = ScanSpec::belcour();
    let order: Vec<u32> = visit_order(&REFERENCE, &spec, PARK).collect();
    let (accepted, mut events) = head.start_scan(&spec).await.unwrap();
    assert_eq!(accepted.points, 3441);
    scan::feed(&head, accepted.run, &order, 0).await.unwrap();
    for _ in 0..5 {
        events.recv().await.unwrap();
    }
    let st = head.request::<AbortEndpoint>(&()).await.unwrap();
    assert_eq!(st.state, HeadState::Idle);
    assert!(!st.laser_on);
    let next = loop {
        match events.recv().await.unwrap() {
            ScanEvent::Stopped { next_order, reason, .. } => {
                assert_eq!(reason, gonio_shared::Fault::Aborted);
                break next_order;
            }
            ScanEvent::Sample(_) | ScanEvent::Skipped { .. } => {}
            ScanEvent::SweptSample(_) | ScanEvent::Swept { .. } => panic!("a scan of points swept"),
            ScanEvent::Finished { .. } => panic!("an aborted scan finished"),
            ScanEvent::Paused { .. } => panic!("an aborted scan was held"),
        }
    };
    assert!(next >= 5);
    drop(events);
    let resumed = ScanSpec { first_order: next, ..spec };
    let (accepted, mut events) = head.start_scan(&resumed).await.unwrap();
    assert_eq!(accepted.first_order, next);
    scan::feed(&head, accepted.run, &order, next).await.unwrap();
    let first = match events.recv().await.unwrap() {
        ScanEvent::Sample(s) => s.scan.unwrap().order,
        ScanEvent::Skipped { order, .. } => order,
        other => panic!("{other:?}"),
    };
    assert_eq!(first, next);
    head.request::<AbortEndpoint>(&()).await.unwrap();
    drop(events);
    head.close().await;
}

/// A simulated head serving on a pseudo-terminal in `dir`, as `gonio sim` runs it.
async fn pty_head(cfg: SimConfig, dir: &std::path::Path) -> Port {
    let link = dir.join("head");
    let serve_at = link.clone();
    std::thread::spawn(move || serve_pty(cfg, &serve_at, |_| {}));
    for _ in 0..200 {
        if link.exists() {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    Port(link.to_string_lossy().into_owned())
}

#[tokio::test]
async fn the_simulated_head_on_a_pseudo_terminal_is_driven_like_a_real_one() {
    let dir = tempfile::tempdir().unwrap();
    let target = pty_head(SimConfig::default(), dir.path()).await;
    let mut session = session(Arc::new(target.clone())).await;
    assert!(session.head().identity().simulated);
    assert_eq!(session.head().identity().protocol_version, PROTOCOL_VERSION);
    let (outcome, rows) = scan_and_read(&mut session, &small_grid(), dir.path()).await;
    assert_eq!(rows.len() as u32, outcome.measured);
    assert_eq!(outcome.measured + outcome.skipped, small_grid().len());
    session.close().await;
    // A second session on the same head works too.
    let again = HeadClient::connect(&target).await.unwrap();
    assert!(again.request::<StatusEndpoint>(&()).await.unwrap().homed);
    again.close().await;
}

/// Over a port, as with a real head: the answer to the scan request is lost
/// (the head scans on, its events go nowhere), then a later request is lost
/// too. Each time the host finds the head again on its port, stops what it
/// was doing, prepares it and continues: every position stored once.
#[tokio::test]
async fn lost_answers_and_requests_over_a_port_are_recovered_by_reconnecting() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = SimConfig {
        // Requests 1–7 identify the head, ask its mechanics and prepare it, 8
        // starts the scan (its answer, frame 8, is lost); the probe is status
        // traffic, not counted. The head found again may already hold that
        // scan (it saw the port close), and is then continued, 16 being one of
        // its visit chunks; or not yet: then 9–15 prepare it again and 16
        // starts the scan. Either way request 16 is lost, and found lost.
        faults: gonio_sim::faults::Faults::parse("drop@8,req-drop@16").unwrap(),
        ..SimConfig::default()
    };
    let mut session = session(Arc::new(pty_head(cfg, dir.path()).await)).await;
    let (outcome, rows) = scan_and_read(&mut session, &small_grid(), dir.path()).await;
    let stored: BTreeSet<u32> = rows.iter().filter_map(|r| r.index).collect();
    assert_eq!(stored.len(), rows.len(), "a position stored twice");
    assert_eq!(stored.len() as u32, outcome.measured);
    assert_eq!(outcome.measured + outcome.skipped, small_grid().len());
    let lost: u32 = outcome
        .recoveries
        .iter()
        .filter(|(k, _)| k.contains("was lost"))
        .map(|(_, n)| n)
        .sum();
    assert_eq!(lost, 2, "{:?}", outcome.recoveries);
    assert_eq!(session.reconnections, 2);
    session.close().await;
}

/// A stop over the pseudo-terminal, as with a real head: the host's port
/// closes while the head moves between two scan points with the laser on.
/// The head sees the terminal hang up, darkens the laser and brakes at
/// once: the stages stand well short of the second point although the
/// move (paced at 20× real time) had most of its 8 s to go. It holds the
/// scan, and a new session continues it.
#[tokio::test]
async fn pulling_the_link_mid_move_darkens_the_laser_and_stops_the_motors_before_the_move_ends() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = SimConfig {
        pace: 0.05,
        ..SimConfig::default()
    };
    let target = pty_head(cfg, dir.path()).await;
    // Two points far apart: the move between them takes 8 s.
    let spec = ScanSpec {
        theta_o: AngleRange::new(80.0, 80.0, 1.0),
        dphi: AngleRange::new(90.0, 90.0, 1.0),
        theta_i_deg: heapless::Vec::from_slice(&[0.0, 80.0]).unwrap(),
        first_order: 0,
        sweep: None,
        patterns: None,
    };
    let [a, b] = [0, 1].map(|i| {
        let axes = kinematics::inverse(&REFERENCE, &spec.point(i).unwrap()).unwrap();
        gonio_firmware::motion::target_steps(&REFERENCE, &axes)
    });
    let move_s = gonio_firmware::motion::move_time(&REFERENCE, [0, 1, 2].map(|i| b[i] - a[i]));
    assert!(move_s > 8.0, "the move between the points takes {move_s} s");
    let head = HeadClient::connect(&target).await.unwrap();
    head.request::<HomeEndpoint>(&HomeRequest::ALL).await.unwrap();
    let (accepted, mut events) = head.start_scan(&spec).await.unwrap();
    scan::feed(&head, accepted.run, &[0, 1], 0).await.unwrap();
    let first = match events.recv().await.unwrap() {
        ScanEvent::Sample(s) => s,
        other => panic!("{other:?}"),
    };
    // 30 ms of wall clock: 0.6 s into the 8 s move on the head's clock
    // (a late wake-up here has 370 ms of margin).
    tokio::time::sleep(Duration::from_millis(30)).await;
    drop(events);
    head.close().await;
    // The operator plugs the cable back a little later (the terminal's
    // hang-up is a level, not an edge: the head must see it).
    tokio::time::sleep(Duration::from_millis(50)).await;
    let again = HeadClient::connect(&target).await.unwrap();
    let st = again.request::<StatusEndpoint>(&()).await.unwrap();
    assert!(matches!(st.state, HeadState::Paused { next_order: 1, .. }), "{:?}", st.state);
    assert!(!st.laser_on, "laser on after the link was pulled");
    assert!(!st.drivers_enabled && st.homed);
    // Stopped, and well short of the second point: the axes no longer move
    // although the move had most of its 8 s to go.
    tokio::time::sleep(Duration::from_millis(50)).await;
    let st2 = again.request::<StatusEndpoint>(&()).await.unwrap();
    assert_eq!(st.axes, st2.axes, "the motors still move");
    let reached = kinematics::forward(&st2.axes);
    assert!(reached.theta_i_deg < 60.0, "the move nearly reached its end: {reached:?}");
    assert_eq!(first.scan.unwrap().order, 0);
    // The held scan continues where it stopped: the second point, then the end.
    let (_, mut events) = again.continue_events().await.unwrap();
    match events.recv().await.unwrap() {
        ScanEvent::Sample(s) => assert_eq!(s.scan.unwrap().order, 1),
        other => panic!("{other:?}"),
    }
    assert!(matches!(events.recv().await.unwrap(), ScanEvent::Finished { run: 1, .. }));
    drop(events);
    again.close().await;
}

/// The simulated head's clock runs by what the head does and what the host
/// asks, never by the host's wall time: a host that thinks for 0.6 s between
/// two requests finds the clock where it left it (it used to run on by the
/// head's 250 ms waking ticks while it waited), and a scan whose laser
/// drifts with that clock, run twice, stores the same samples.
#[tokio::test]
async fn the_simulated_clock_does_not_follow_the_hosts_wall_time() {
    let head = HeadClient::connect(&Simulated(SimConfig::default())).await.unwrap();
    let before = head.request::<StatusEndpoint>(&()).await.unwrap().uptime_us;
    tokio::time::sleep(Duration::from_millis(600)).await;
    let after = head.request::<StatusEndpoint>(&()).await.unwrap().uptime_us;
    assert!(
        after - before < 1_000,
        "the head's clock ran {} µs while the host thought",
        after - before
    );
    drop(head);

    let mut sim = SimConfig::default();
    sim.photodiode.laser_drift = 0.05;
    let mut runs = Vec::new();
    for _ in 0..2 {
        let mut session = session(Arc::new(Simulated(sim.clone()))).await;
        let dir = tempfile::tempdir().unwrap();
        let (outcome, rows) = scan_and_read(&mut session, &small_grid(), dir.path()).await;
        session.close().await;
        runs.push((outcome.head_time_s, format!("{rows:?}")));
    }
    assert_eq!(runs[0], runs[1], "two runs of one scan differ");
}
