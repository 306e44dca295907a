//! Firmware drivers against `embedded-hal-mock`: every pin transaction and
//! every delay is checked, in order, for homing and for the detector's gain
//! switching.

use embedded_hal_mock::eh1::delay::{CheckedDelay, Transaction as Delay};
use embedded_hal_mock::eh1::digital::{State, Transaction as Pin};
use futures::executor::block_on;
use gonio_firmware::config::REFERENCE;
use gonio_firmware::detector::Detector;
use gonio_firmware::homing::{self, home_axis};
use gonio_firmware::motion::Position;
use gonio_firmware::units;
use gonio_shared::{Axis, DetectionSettings, Fault, Field, Reference as Kind, SampleFlags};
use gonio_tests::doubles::{chop_period, done, expect, Pins, ScriptedAdc, SCRIPTED_TIMER_HZ};

/// The delays of `n` homing chunks, as the core asks for them: each a move
/// (the drivers' DIR setup time before its first step and hold time after
/// its last), then the home input's settling before it is read.
fn homing_chunks(n: usize) -> Vec<Delay> {
    let ns = |s: f32| Delay::async_delay_ns(units::seconds_to_ns(s));
    let d = &REFERENCE.driver;
    (0..n)
        .flat_map(|_| [ns(d.dir_setup_s), ns(d.dir_hold_s), ns(homing::SWITCH_SETTLE_S)])
        .collect()
}

/// Microsteps of one fast homing chunk of the rotation stage (0.5°).
fn fast_chunk() -> u32 {
    units::deg_to_steps(&REFERENCE.axes[0], 0.5) as u32
}

#[test]
fn homing_finds_the_switch_backs_off_and_touches_slowly() {
    let mut pins = Pins::idle();
    // Open, open, closed (after two fast chunks); still closed, open (after
    // one back-off chunk); open, closed (after one slow chunk); then the
    // edge: closed, open (one microstep off it); open, closed (one back on).
    expect(
        &mut pins.home[0],
        &[
            Pin::get(State::Low),
            Pin::get(State::Low),
            Pin::get(State::High),
            Pin::get(State::High),
            Pin::get(State::Low),
            Pin::get(State::Low),
            Pin::get(State::High),
            Pin::get(State::High),
            Pin::get(State::Low),
            Pin::get(State::Low),
            Pin::get(State::High),
        ],
    );
    // DIR towards the switch (low) twice, away once, towards once, away and
    // towards for the edge; the driver enabled (active low) before every chunk.
    expect(
        &mut pins.dir[0],
        &[
            Pin::set(State::Low),
            Pin::set(State::Low),
            Pin::set(State::High),
            Pin::set(State::Low),
            Pin::set(State::High),
            Pin::set(State::Low),
        ],
    );
    expect(&mut pins.enable_n[0], &vec![Pin::set(State::Low); 6]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&homing_chunks(6)));
    let mut pos = Position::default();
    block_on(home_axis(&mut hw, &REFERENCE, &mut pos, Axis::Rotation)).unwrap();

    let c = &REFERENCE.axes[0];
    assert!(pos.homed[0] && !pos.homed[1] && !pos.homed[2]);
    assert_eq!(pos.steps[0], units::deg_to_steps(c, c.home_deg));
    let counts: Vec<u32> = hw.steps.runs.iter().map(|r| r.iter().map(|(_, b)| b.count).sum()).collect();
    assert_eq!(counts, vec![fast_chunk(), fast_chunk(), fast_chunk(), 4, 1, 1]);
    assert!(hw.steps.runs.iter().flatten().all(|(a, _)| *a == Axis::Rotation));
    done(&mut hw);
}

#[test]
fn homing_faults_when_the_switch_never_closes() {
    let c = &REFERENCE.axes[0];
    let travel = units::deg_to_steps(c, c.max_deg - c.home_deg + 2.0 * c.home_backoff_deg) as u32;
    let chunks = travel.div_ceil(fast_chunk()) as usize;
    let mut pins = Pins::idle();
    expect(&mut pins.home[0], &vec![Pin::get(State::Low); chunks + 1]);
    expect(&mut pins.dir[0], &vec![Pin::set(State::Low); chunks]);
    expect(&mut pins.enable_n[0], &vec![Pin::set(State::Low); chunks]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&homing_chunks(chunks)));
    let mut pos = Position::default();
    let r = block_on(home_axis(&mut hw, &REFERENCE, &mut pos, Axis::Rotation));
    assert_eq!(r, Err(Fault::HomeSwitchNotFound(Axis::Rotation)));
    assert!(!pos.homed[0]);
    // It never went further than the whole travel plus one chunk.
    assert!(hw.steps.steps(Axis::Rotation) <= travel + fast_chunk());
    done(&mut hw);
}

#[test]
fn homing_faults_when_the_switch_is_stuck_closed() {
    let c = &REFERENCE.axes[0];
    let backoff_chunks = (units::deg_to_steps(c, c.home_backoff_deg) as u32).div_ceil(fast_chunk()) as usize;
    let mut pins = Pins::idle();
    expect(&mut pins.home[0], &vec![Pin::get(State::High); backoff_chunks + 2]);
    expect(&mut pins.dir[0], &vec![Pin::set(State::High); backoff_chunks]);
    expect(&mut pins.enable_n[0], &vec![Pin::set(State::Low); backoff_chunks]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&homing_chunks(backoff_chunks)));
    let mut pos = Position::default();
    let r = block_on(home_axis(&mut hw, &REFERENCE, &mut pos, Axis::Rotation));
    assert_eq!(r, Err(Fault::HomeSwitchStuck(Axis::Rotation)));
    done(&mut hw);
}

fn gain_bits(g: u8) -> [Pin; 2] {
    let s = |on| Pin::set(if on { State::High } else { State::Low });
    [s(g & 1 != 0), s(g & 2 != 0)]
}

#[test]
fn auto_range_steps_up_to_the_gain_that_fits_and_reports_it() {
    let m = 64;
    let s = DetectionSettings {
        periods: 4,
        ..DetectionSettings::default()
    };
    // Gain 0: a weak chop (peak 150 codes) → up; gain 1: peak 1500 codes
    // leaves no room for ×10 → stay, and integrate.
    let mut adc = ScriptedAdc::default();
    adc.periods.push_back(chop_period(m, 100, 150)); // settle (discarded)
    adc.periods.push_back(chop_period(m, 100, 150)); // look: raise
    adc.periods.push_back(chop_period(m, 1000, 9)); // settle after the change (discarded)
    adc.periods.push_back(chop_period(m, 1000, 1500)); // look: keep
    adc.periods.push_back(chop_period(m, 1000, 1500)); // settle before integrating
    for _ in 0..4 {
        adc.periods.push_back(chop_period(m, 1000, 1500));
    }
    let mut pins = Pins::idle();
    let [g0a, g1a] = gain_bits(0);
    let [g0b, g1b] = gain_bits(1);
    expect(&mut pins.gain[0], &[g0a, g0b]);
    expect(&mut pins.gain[1], &[g1a, g1b]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&[]));
    hw.adc = adc;
    let mut det = Detector::new(s, SCRIPTED_TIMER_HZ);
    let meas = block_on(det.measure(&mut hw, &REFERENCE)).unwrap();
    assert_eq!(meas.gain_index, 1);
    assert_eq!(meas.gain_v_per_a, REFERENCE.detector.gains_v_per_a[1]);
    assert_eq!(meas.periods, 4);
    let volts = units::codes_to_volts(500.0, 12, REFERENCE.detector.adc_vref);
    assert!((meas.amplitude_v - volts).abs() < 1e-6, "{meas:?}");
    assert_eq!(meas.flags, SampleFlags::default());
    assert_eq!(hw.adc.started.len(), 1);
    assert!(hw.adc.periods.is_empty());
    done(&mut hw);
}

#[test]
fn saturation_at_the_lowest_gain_is_flagged_and_an_empty_stream_is_an_overrun() {
    let m = 64;
    let s = DetectionSettings {
        periods: 2,
        ..DetectionSettings::default()
    };
    let mut adc = ScriptedAdc::default();
    for _ in 0..4 {
        adc.periods.push_back(chop_period(m, 2000, 4095));
    }
    let mut pins = Pins::idle();
    let [g0, g1] = gain_bits(0);
    expect(&mut pins.gain[0], &[g0]);
    expect(&mut pins.gain[1], &[g1]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&[]));
    hw.adc = adc;
    let mut det = Detector::new(s, SCRIPTED_TIMER_HZ);
    let meas = block_on(det.measure(&mut hw, &REFERENCE)).unwrap();
    assert_eq!(meas.gain_index, 0);
    assert!(meas.flags.contains(SampleFlags::SATURATED));
    // The script ran dry during integration: the lost block is flagged.
    assert!(meas.flags.contains(SampleFlags::OVERRUN));
    done(&mut hw);
}

/// `periods` chop periods of `m` codes delayed by `delay` samples.
fn delayed(m: usize, low: u16, high: u16, delay: usize, periods: usize) -> Vec<Vec<u16>> {
    let p: Vec<u16> = (0..m).map(|k| if (k + m - delay) % m < m / 2 { high } else { low }).collect();
    vec![p; periods]
}

#[test]
fn learning_finds_the_phase_and_the_matched_reference_round_trips() {
    let m = 64;
    let s = DetectionSettings {
        periods: 23,
        auto_range: false,
        ..DetectionSettings::default()
    };
    let mut pins = Pins::idle();
    // The gain (0) is written each time the chop starts: learning, then
    // the first measurement after the reconfiguration.
    let [a, b] = gain_bits(0);
    let [c, d] = gain_bits(0);
    expect(&mut pins.gain[0], &[a, c]);
    expect(&mut pins.gain[1], &[b, d]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&[]));
    let mut det = Detector::new(s, SCRIPTED_TIMER_HZ);
    let matched = DetectionSettings {
        reference: Kind::Matched,
        ..s
    };
    assert_eq!(det.configure(&mut hw, &REFERENCE, matched), Err(Fault::NotLearned));

    // Learn on a strong chop delayed by d = 4 of 64 samples. Against the
    // square references that is I ∝ 32 − 2d and Q ∝ 2d.
    hw.adc.periods.extend(delayed(m, 1000, 2500, 4, 1 + 230));
    let report = block_on(det.learn(&mut hw, &REFERENCE, 230)).unwrap();
    let want = 8f32.atan2(24.0).to_degrees();
    assert!((report.phase_deg - want).abs() < 1e-3, "{report:?}");
    assert!(report.snr > 1e3);
    det.configure(&mut hw, &REFERENCE, matched).unwrap();

    // A third of the amplitude, same delay: a third of the amplitude, in phase.
    hw.adc.periods.extend(delayed(m, 1000, 1500, 4, 1 + 23));
    let weak = block_on(det.measure(&mut hw, &REFERENCE)).unwrap();
    hw.adc.periods.extend(delayed(m, 1000, 2500, 4, 1 + 23));
    let strong = block_on(det.measure(&mut hw, &REFERENCE)).unwrap();
    assert!(
        (weak.amplitude_v / strong.amplitude_v - 1.0 / 3.0).abs() < 1e-3,
        "{weak:?} {strong:?}"
    );
    assert!(!weak.flags.contains(SampleFlags::PHASE_OFF));

    // A quarter period later than learned: flagged as off phase.
    hw.adc.periods.extend(delayed(m, 1000, 2500, 20, 1 + 23));
    let late = block_on(det.measure(&mut hw, &REFERENCE)).unwrap();
    assert!(late.flags.contains(SampleFlags::PHASE_OFF), "{late:?}");
    done(&mut hw);
}

#[test]
fn learning_refuses_a_weak_or_short_signal() {
    let s = DetectionSettings {
        auto_range: false,
        ..DetectionSettings::default()
    };
    let mut pins = Pins::idle();
    let [a, b] = gain_bits(0);
    expect(&mut pins.gain[0], &[a]);
    expect(&mut pins.gain[1], &[b]);
    let mut hw = pins.into_hardware(CheckedDelay::new(&[]));
    let mut det = Detector::new(s, SCRIPTED_TIMER_HZ);
    assert_eq!(
        block_on(det.learn(&mut hw, &REFERENCE, 3)),
        Err(Fault::InvalidValue(Field::Periods))
    );
    // No chop at all: nothing to learn from.
    hw.adc.periods.extend(delayed(64, 1000, 1000, 0, 1 + 50));
    assert_eq!(block_on(det.learn(&mut hw, &REFERENCE, 50)), Err(Fault::WeakSignal));
    done(&mut hw);
}

/// A trigger rate the ADC cannot convert (84-cycle
/// sampling at 21 MHz: 218.75 kS/s) is refused instead of losing samples
/// silently; the default settings and the highest accepted rate fit.
#[test]
fn sample_rates_beyond_the_adc_conversion_rate_are_refused() {
    let d = DetectionSettings::default();
    let at = |chop_hz: f32, samples_per_period: u16| DetectionSettings {
        chop_hz,
        samples_per_period,
        ..d
    };
    assert!(d.validate().is_ok() && d.sample_rate_hz() < DetectionSettings::ADC_RATE_MAX_HZ);
    // 390.625 Hz × 512 = 200 kS/s: the highest rate accepted, below what converts.
    assert!(at(390.625, 512).validate().is_ok());
    for (chop, m) in [(450.0, 512), (1000.0, 256), (800.0, 512)] {
        assert!(at(chop, m).sample_rate_hz() > DetectionSettings::ADC_RATE_MAX_HZ);
        assert_eq!(
            at(chop, m).validate(),
            Err(Fault::InvalidValue(Field::SamplesPerPeriod)),
            "{chop} Hz × {m}"
        );
    }
}
