//! Measuring while moving, on the simulated head driven directly: the
//! photodiode sees the true motor positions at every conversion, each
//! swept sample's tag (from the step counts) matches the mean geometry it
//! really saw, its signal matches a measurement at rest there, and a sweep
//! of three axes keeps to a straight line in axis space.

use gonio_shared::{DetectionSettings, Fault, Field, Geometry, SweepRequest, Unreachable};
use gonio_sim::faults::Faults;
use gonio_sim::SimConfig;
use gonio_tests::sweeping::{conversions, geometry, tag_error_deg_max, SimHead};

/// A sweep of θo in the retro half-plane at θi = 30°, clear of the peak
/// and of the plate's shadow (11.5° from the laser).
fn arc(speed_dps: f32) -> SweepRequest {
    SweepRequest {
        from: Geometry::new(30.0, 42.0, 0.0),
        to: Geometry::new(30.0, 70.0, 0.0),
        speed_dps,
        periods_per_sample: 8,
    }
}

#[test]
fn swept_samples_are_tagged_where_the_stages_were_and_read_what_a_sample_at_rest_reads() {
    let mut sim = SimHead::homed(&SimConfig::default());
    let swept = sim.sweep(arc(4.0)).unwrap();
    let (samples, log) = (&swept.samples, &swept.log);
    assert_eq!(swept.report.samples as usize, samples.len());
    assert!(samples.len() > 100, "{} samples over 28° at 4°/s", samples.len());
    assert!((swept.report.reached.theta_o_deg - 70.0).abs() < 1e-3, "{:?}", swept.report);

    // The conversions saw the motors move within a period.
    let changes = log.windows(2).filter(|w| w[0].1 != w[1].1).count();
    assert!(changes > 1000, "the motor angles changed {changes} times between conversions");

    let m = gonio_shared::DetectionSettings::default().samples_per_period as usize;
    for s in samples {
        assert_eq!(conversions(log, s).len(), s.signal.periods as usize * m, "conversions of {s:?}");
    }
    let worst = tag_error_deg_max(&swept);
    assert!(worst <= 0.01, "tag error {worst}°");
    // Samples follow each other along the arc, each with its extent.
    for w in samples.windows(2) {
        assert_eq!(w[1].axes_from, w[0].axes_to, "consecutive samples share their boundary");
        assert!(w[1].mid_axes().psi_deg > w[0].mid_axes().psi_deg);
        assert_eq!(w[1].seq, w[0].seq + 1);
    }

    // A few swept samples against a measurement at rest at their middle.
    for s in samples.iter().step_by(samples.len() / 5).skip(1) {
        let mid = geometry(&s.mid_axes());
        let still = sim.measure(mid).unwrap();
        let (a, b) = (s.signal.amplitude_v as f64, still.signal.amplitude_v as f64);
        let sigma = (s.signal.noise_v as f64).hypot(still.signal.noise_v as f64);
        assert!((a - b).abs() <= 3.0 * sigma, "swept {a} V, at rest {b} V (σ {sigma} V) at {mid:?}");
    }
}

#[test]
fn a_sweep_of_three_axes_follows_a_straight_line_in_axis_space() {
    let mut sim = SimHead::homed(&SimConfig::default());
    let swept = sim
        .sweep(SweepRequest {
            from: Geometry::new(20.0, 40.0, 30.0),
            to: Geometry::new(50.0, 65.0, 100.0),
            speed_dps: 6.0,
            periods_per_sample: 4,
        })
        .unwrap();
    let (a, b) = (swept.samples[0].axes_from, swept.samples.last().unwrap().axes_to);
    let (a, b) = ([a.omega_deg, a.tau_deg, a.psi_deg], [b.omega_deg, b.tau_deg, b.psi_deg]);
    let span = [0, 1, 2].map(|i| (b[i] - a[i]) as f64);
    assert!(span.iter().all(|d| d.abs() > 1.0), "every axis moves: {span:?}");
    let main = (0..3).max_by(|&i, &j| span[i].abs().total_cmp(&span[j].abs())).unwrap();
    let t0 = swept.samples[0].start_us as f64 * 1e-6;
    let mut worst: f64 = 0.0;
    for (_, m) in swept.log.iter().filter(|(t, _)| *t >= t0) {
        let f = (m[main] - a[main] as f64) / span[main];
        for i in 0..3 {
            worst = worst.max((m[i] - (a[i] as f64 + f * span[i])).abs());
        }
    }
    // A few microsteps (1/1600°) off the line at most, ramps included.
    assert!(worst < 0.005, "{worst}° off the straight line");
    assert!(tag_error_deg_max(&swept) <= 0.01);
}

#[test]
fn sweeps_through_the_blind_zone_or_beyond_the_axes_are_refused_before_moving() {
    let mut sim = SimHead::homed(&SimConfig::default());
    let before = sim.world.borrow().steps;
    let refused = |sim: &mut SimHead, req| sim.sweep(req).err().expect("refused");
    let across = SweepRequest {
        // From the retro direction (seen through the splitter) outwards.
        from: Geometry::new(30.0, 30.0, 0.0),
        to: Geometry::new(30.0, 40.0, 0.0),
        ..arc(4.0)
    };
    assert_eq!(refused(&mut sim, across), Fault::Unreachable(Unreachable::BlindZone));
    assert_eq!(refused(&mut sim, arc(1e4)), Fault::InvalidValue(Field::SweepSpeed));
    let short = SweepRequest {
        periods_per_sample: 1,
        ..arc(4.0)
    };
    assert_eq!(refused(&mut sim, short), Fault::InvalidValue(Field::Periods));
    let beyond = SweepRequest {
        to: Geometry::new(87.0, 87.0, 180.0),
        ..arc(4.0)
    };
    assert!(matches!(refused(&mut sim, beyond), Fault::Unreachable(Unreachable::AxisTravel(_))));
    assert_eq!(sim.world.borrow().steps, before);
    let st = sim.head.status();
    assert!(!st.laser_on && st.last_fault.is_none(), "a refused sweep changed the head: {st:?}");
}

#[test]
fn a_sweep_that_stalls_or_loses_a_block_stops_dark_and_says_where_the_axes_are() {
    // The sweep's move is the first the laser sees.
    let stalled = SimConfig {
        faults: Faults::parse("stall@1").unwrap(),
        ..SimConfig::default()
    };
    let mut sim = SimHead::homed(&stalled);
    assert!(matches!(sim.sweep(arc(4.0)).err(), Some(Fault::StepTimer(_))));
    let st = sim.head.status();
    assert!(!st.laser_on && !st.homed, "after a stall the axes need homing: {st:?}");

    let lost = SimConfig {
        faults: Faults::parse("overrun@1:1").unwrap(),
        ..SimConfig::default()
    };
    let mut sim = SimHead::homed(&lost);
    assert_eq!(sim.sweep(arc(4.0)).err(), Some(Fault::AdcOverrun));
    let st = sim.head.status();
    assert!(!st.laser_on && st.homed, "a lost block brakes the move, steps counted: {st:?}");
    // The head knows where the braked axes are: a move from there lands.
    let g = Geometry::new(30.0, 50.0, 0.0);
    let at_rest = sim.measure(g).unwrap();
    assert!((at_rest.reached.theta_o_deg - 50.0).abs() < 1e-3, "{:?}", at_rest.reached);
    assert_eq!(sim.motor_geometry(), at_rest.reached);
}

/// A chop faster than the thread can read the ADC's ring at (two periods)
/// is refused with the settings, for sweeps and points alike; the fastest
/// one sweeps.
#[test]
fn a_chop_too_fast_for_the_adc_ring_is_refused() {
    let mut sim = SimHead::homed(&SimConfig::default());
    let at = |chop_hz| DetectionSettings {
        chop_hz,
        ..DetectionSettings::default()
    };
    let too_fast = at(DetectionSettings::CHOP_HZ_MAX * 1.01);
    assert_eq!(
        sim.head.configure_detection(too_fast).err(),
        Some(Fault::InvalidValue(Field::ChopFrequency))
    );
    sim.head.configure_detection(at(DetectionSettings::CHOP_HZ_MAX)).unwrap();
    assert!(sim.sweep(arc(4.0)).is_ok());
}
