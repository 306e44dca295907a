//! Measuring while moving, on the simulated head driven directly: the
//! photodiode sees the true motor positions at every conversion, each
//! swept sample's tag (from the step counts) matches the mean geometry it
//! really saw, and its signal matches a measurement at rest there.

use gonio_firmware::kinematics;
use gonio_shared::icd::{HomeRequest, MeasureRequest};
use gonio_shared::{AxisAngles, Fault, Geometry, SweepRequest, SweptSample, Unreachable};
use gonio_sim::{build, clock, SimConfig};

/// A sweep of θo in the retro half-plane at θi = 30°, clear of the peak.
fn arc(speed_dps: f32) -> SweepRequest {
    SweepRequest {
        from: Geometry::new(30.0, 40.0, 0.0),
        to: Geometry::new(30.0, 70.0, 0.0),
        speed_dps,
        periods_per_sample: 8,
    }
}

/// The mean geometry over the conversions a swept sample integrated, from
/// the true motor angles the simulated head logged at each of them.
fn true_mean(log: &[(f64, [f64; 3])], s: &SweptSample) -> (Geometry, usize) {
    let t0 = s.start_us as f64 * 1e-6 - 1e-6;
    let t1 = t0 + s.duration_s as f64;
    let seen: Vec<Geometry> = log
        .iter()
        .filter(|(t, _)| *t >= t0 && *t < t1)
        .map(|(_, a)| {
            kinematics::forward(&AxisAngles {
                omega_deg: a[0] as f32,
                tau_deg: a[1] as f32,
                psi_deg: a[2] as f32,
            })
        })
        .collect();
    let n = seen.len().max(1) as f64;
    let mean = |f: fn(&Geometry) -> f32| (seen.iter().map(|g| f(g) as f64).sum::<f64>() / n) as f32;
    (
        Geometry::new(mean(|g| g.theta_i_deg), mean(|g| g.theta_o_deg), mean(|g| g.dphi_deg)),
        seen.len(),
    )
}

#[test]
fn swept_samples_are_tagged_where_the_stages_were_and_read_what_a_sample_at_rest_reads() {
    let (mut head, world) = build(&SimConfig::default());
    clock::run(&world, head.home(HomeRequest::ALL)).unwrap();
    world.borrow_mut().sample_log = Some(Vec::new());
    let mut swept = Vec::new();
    let report = clock::run(&world, head.sweep(arc(4.0), |s| swept.push(s))).unwrap();
    let log = world.borrow_mut().sample_log.take().unwrap();
    assert_eq!(report.samples as usize, swept.len());
    assert!(swept.len() > 100, "{} samples over 30° at 4°/s", swept.len());
    assert!((report.reached.theta_o_deg - 70.0).abs() < 1e-3, "{report:?}");

    // The conversions saw the motors move within a period.
    let periods_seen = log.windows(2).filter(|w| w[0].1 != w[1].1).count();
    assert!(
        periods_seen > 1000,
        "the motor angles changed {periods_seen} times between conversions"
    );

    let m = gonio_shared::DetectionSettings::default().samples_per_period as usize;
    let mut worst: f32 = 0.0;
    for s in &swept {
        let (mean, n) = true_mean(&log, s);
        assert_eq!(n, s.signal.periods as usize * m, "conversions of {s:?}");
        let mid = kinematics::forward(&s.mid_axes());
        for (tagged, true_deg) in [
            (mid.theta_i_deg, mean.theta_i_deg),
            (mid.theta_o_deg, mean.theta_o_deg),
            (mid.dphi_deg, mean.dphi_deg),
        ] {
            worst = worst.max((tagged - true_deg).abs());
        }
    }
    assert!(worst <= 0.01, "tag error {worst}°");
    // Samples follow each other along the arc, each with its extent.
    for w in swept.windows(2) {
        assert_eq!(w[1].axes_from, w[0].axes_to, "consecutive samples share their boundary");
        assert!(w[1].mid_axes().psi_deg > w[0].mid_axes().psi_deg);
        assert!(w[1].seq == w[0].seq + 1);
    }

    // A few swept samples against a measurement at rest at their middle.
    for s in swept.iter().step_by(swept.len() / 5).skip(1) {
        let mid = kinematics::forward(&s.mid_axes());
        let still = clock::run(&world, head.measure(MeasureRequest { at: Some(mid) })).unwrap();
        let (a, b) = (s.signal.amplitude_v as f64, still.signal.amplitude_v as f64);
        let sigma = (s.signal.noise_v as f64).hypot(still.signal.noise_v as f64);
        assert!((a - b).abs() <= 3.0 * sigma, "swept {a} V, at rest {b} V (σ {sigma} V) at {mid:?}");
    }
}

#[test]
fn a_sweep_of_three_axes_follows_a_straight_line_in_axis_space() {
    let (mut head, world) = build(&SimConfig::default());
    clock::run(&world, head.home(HomeRequest::ALL)).unwrap();
    world.borrow_mut().sample_log = Some(Vec::new());
    let req = SweepRequest {
        from: Geometry::new(20.0, 40.0, 30.0),
        to: Geometry::new(50.0, 65.0, 100.0),
        speed_dps: 6.0,
        periods_per_sample: 4,
    };
    let mut swept = Vec::new();
    clock::run(&world, head.sweep(req, |s| swept.push(s))).unwrap();
    let log = world.borrow_mut().sample_log.take().unwrap();
    let (a, b) = (swept[0].axes_from, swept.last().unwrap().axes_to);
    let (a, b) = ([a.omega_deg, a.tau_deg, a.psi_deg], [b.omega_deg, b.tau_deg, b.psi_deg]);
    let span = [0, 1, 2].map(|i| (b[i] - a[i]) as f64);
    assert!(span.iter().all(|d| d.abs() > 1.0), "every axis moves: {span:?}");
    let main = (0..3).max_by(|&i, &j| span[i].abs().total_cmp(&span[j].abs())).unwrap();
    let t0 = swept[0].start_us as f64 * 1e-6;
    let mut worst: f64 = 0.0;
    for (_, m) in log.iter().filter(|(t, _)| *t >= t0) {
        let f = (m[main] - a[main] as f64) / span[main];
        for i in 0..3 {
            worst = worst.max((m[i] - (a[i] as f64 + f * span[i])).abs());
        }
    }
    // A few microsteps (1/1600°) off the line at most, ramps included.
    assert!(worst < 0.005, "{worst}° off the straight line");
}

#[test]
fn sweeps_through_the_blind_zone_or_beyond_the_axes_are_refused_before_moving() {
    let (mut head, world) = build(&SimConfig::default());
    clock::run(&world, head.home(HomeRequest::ALL)).unwrap();
    let before = world.borrow().steps;
    let across = SweepRequest {
        // From the retro direction (seen through the splitter) outwards.
        from: Geometry::new(30.0, 30.0, 0.0),
        to: Geometry::new(30.0, 40.0, 0.0),
        ..arc(4.0)
    };
    let r = clock::run(&world, head.sweep(across, |_| panic!("nothing is measured")));
    assert_eq!(r, Err(Fault::Unreachable(Unreachable::BlindZone)));
    let r = clock::run(&world, head.sweep(arc(1e4), |_| panic!("nothing is measured")));
    assert_eq!(r, Err(Fault::InvalidValue(gonio_shared::Field::SweepSpeed)));
    let r = clock::run(
        &world,
        head.sweep(
            SweepRequest {
                periods_per_sample: 1,
                ..arc(4.0)
            },
            |_| panic!("nothing is measured"),
        ),
    );
    assert_eq!(r, Err(Fault::InvalidValue(gonio_shared::Field::Periods)));
    let beyond = SweepRequest {
        to: Geometry::new(87.0, 87.0, 180.0),
        ..arc(4.0)
    };
    let r = clock::run(&world, head.sweep(beyond, |_| panic!("nothing is measured")));
    assert!(matches!(r, Err(Fault::Unreachable(Unreachable::AxisTravel(_)))), "{r:?}");
    assert_eq!(world.borrow().steps, before);
    let st = head.status();
    assert!(!st.laser_on && st.last_fault.is_none(), "a refused sweep changed the head: {st:?}");
}
