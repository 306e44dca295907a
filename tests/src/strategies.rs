//! Proptest strategies for the messages of `gonio-shared`, covering the whole
//! range of every field (NaN and infinities included for floats: the codec
//! must carry whatever a buggy peer sends, validation refuses it later).

use gonio_shared::icd::{HomeRequest, MeasureRequest, MoveReport};
use gonio_shared::sample::ScanPosition;
use gonio_shared::*;
use proptest::prelude::*;

pub fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => -1.0e6f32..1.0e6,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => any::<f32>(),
    ]
}

pub fn geometry() -> impl Strategy<Value = Geometry> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(a, b, c)| Geometry::new(a, b, c))
}

pub fn axis_angles() -> impl Strategy<Value = AxisAngles> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(omega_deg, tau_deg, psi_deg)| AxisAngles {
        omega_deg,
        tau_deg,
        psi_deg,
    })
}

pub fn axis() -> impl Strategy<Value = Axis> {
    prop_oneof![Just(Axis::Rotation), Just(Axis::Cradle), Just(Axis::Arm)]
}

pub fn field() -> impl Strategy<Value = Field> {
    prop_oneof![
        Just(Field::ThetaI),
        Just(Field::ThetaO),
        Just(Field::Dphi),
        Just(Field::ChopFrequency),
        Just(Field::SamplesPerPeriod),
        Just(Field::Periods),
        Just(Field::SettleTime),
        Just(Field::ScanRange),
        Just(Field::ScanStart),
        Just(Field::ModelParameter),
        Just(Field::Tolerance),
        Just(Field::HostTimeout),
    ]
}

pub fn fault() -> impl Strategy<Value = Fault> {
    prop_oneof![
        field().prop_map(Fault::InvalidValue),
        Just(Fault::Unreachable(Unreachable::BehindSample)),
        Just(Fault::Unreachable(Unreachable::BlindZone)),
        axis().prop_map(|a| Fault::Unreachable(Unreachable::AxisTravel(a))),
        Just(Fault::NotHomed),
        Just(Fault::Busy),
        Just(Fault::Aborted),
        axis().prop_map(Fault::HomeSwitchNotFound),
        axis().prop_map(Fault::HomeSwitchStuck),
        axis().prop_map(Fault::StepTimer),
        Just(Fault::AdcOverrun),
        Just(Fault::Saturated),
        Just(Fault::Gpio),
        Just(Fault::NotLearned),
        Just(Fault::WeakSignal),
        Just(Fault::NoSignal),
        Just(Fault::HostSilent),
        Just(Fault::WatchdogReset),
        (any::<u32>(), any::<u32>()).prop_map(|(measured_khz, expected_khz)| Fault::Crystal {
            measured_khz,
            expected_khz
        }),
        Just(Fault::ClockStopped),
        any::<i16>().prop_map(Fault::StrayInterrupt),
        Just(Fault::LaserDisabled),
    ]
}

pub fn detection_settings() -> impl Strategy<Value = DetectionSettings> {
    let reference = prop_oneof![Just(Reference::Square), Just(Reference::Sine), Just(Reference::Matched)];
    (any_f32(), any::<u16>(), any::<u16>(), any_f32(), reference, any::<bool>()).prop_map(|(chop_hz, m, k, settle, reference, auto)| {
        DetectionSettings {
            chop_hz,
            samples_per_period: m,
            periods: k,
            settle_s: settle,
            reference,
            auto_range: auto,
        }
    })
}

/// Boxed: the nested tuple strategies are deep enough to overflow a debug
/// test thread's stack otherwise.
pub fn sample() -> BoxedStrategy<Sample> {
    (
        (
            any::<u32>(),
            proptest::option::of((any::<u32>(), any::<u32>())),
            any::<u64>(),
            geometry(),
            geometry(),
            axis_angles(),
        )
            .boxed(),
        (any_f32(), any_f32(), any_f32(), any_f32(), any_f32(), any_f32()).boxed(),
        (any::<u8>(), any::<u16>(), any::<u16>(), any_f32()).boxed(),
    )
        .prop_map(
            |((seq, scan, ts, target, reached, axes), (i, q, a, ph, n, g), (gi, periods, flags, mag))| Sample {
                seq,
                scan: scan.map(|(index, order)| ScanPosition { index, order }),
                timestamp_us: ts,
                target,
                reached,
                axes,
                signal: Signal {
                    in_phase_v: i,
                    quadrature_v: q,
                    amplitude_v: a,
                    magnitude_v: mag,
                    phase_deg: ph,
                    noise_v: n,
                    gain_v_per_a: g,
                    gain_index: gi,
                    periods,
                    flags: SampleFlags::from_bits_retain(flags),
                },
            },
        )
        .boxed()
}

pub fn scan_spec() -> impl Strategy<Value = ScanSpec> {
    (
        proptest::collection::vec(any_f32(), 0..=8),
        (any_f32(), any_f32(), any_f32()),
        (any_f32(), any_f32(), any_f32()),
        any::<u32>(),
        proptest::option::of((any_f32(), any::<u16>(), proptest::option::of((any_f32(), any_f32())))),
    )
        .prop_map(|(ti, (a, b, c), (d, e, f), first_order, sweep)| ScanSpec {
            theta_i_deg: heapless::Vec::from_slice(&ti).unwrap_or_default(),
            theta_o: AngleRange::new(a, b, c),
            dphi: AngleRange::new(d, e, f),
            first_order,
            sweep: sweep.map(|(speed_dps, periods_per_sample, lobe)| SweepScan {
                speed_dps,
                periods_per_sample,
                lobe: lobe.map(|(width_deg, extent_fraction)| SweepLobe {
                    width_deg,
                    extent_fraction,
                }),
            }),
            patterns: None,
        })
}

/// A swept sample: a sample's fields, a length and a second tag.
pub fn swept_sample() -> impl Strategy<Value = SweptSample> {
    (sample(), axis_angles(), any_f32()).prop_map(|(s, axes_to, duration_s)| SweptSample {
        seq: s.seq,
        scan: s.scan,
        start_us: s.timestamp_us,
        duration_s,
        axes_from: s.axes,
        axes_to,
        signal: s.signal,
    })
}

pub fn sanity_config() -> impl Strategy<Value = SanityConfig> {
    let model = (0usize..3, proptest::collection::vec(any_f32(), 8), any::<bool>()).prop_map(|(k, p, back)| {
        let kind = [SanityKind::Lambert, SanityKind::RetroPhong, SanityKind::AbcRetro { back }][k];
        SanityModel::from_params(kind, &p[..kind.arity()]).expect("arity")
    });
    (model, (any_f32(), any_f32()), any_f32(), any_f32(), any_f32(), any::<bool>()).prop_map(|(model, (c, s), r, a, k, remeasure)| {
        SanityConfig {
            model,
            current_a_per_sr_inv: c,
            splitter_factor: s,
            rel_tol: r,
            abs_tol_v: a,
            k_noise: k,
            remeasure,
        }
    })
}

pub fn status() -> impl Strategy<Value = Status> {
    (
        prop_oneof![
            Just(HeadState::Idle),
            Just(HeadState::Homing),
            Just(HeadState::Moving),
            Just(HeadState::Measuring),
            Just(HeadState::Stopping),
            Just(HeadState::Faulted),
            (any::<u32>(), any::<u32>()).prop_map(|(n, t)| HeadState::Scanning { next_order: n, total: t }),
            (any::<u32>(), any::<u32>(), any::<u32>()).prop_map(|(r, n, t)| HeadState::Paused {
                run: r,
                next_order: n,
                total: t
            })
        ],
        (
            any::<bool>(),
            any::<bool>(),
            axis_angles(),
            detection_settings(),
            any::<bool>(),
            any::<bool>(),
        ),
        (
            any::<u32>(),
            any::<u32>(),
            any::<u32>(),
            any::<bool>(),
            proptest::option::of(fault()),
            proptest::option::of(fault()),
            any::<u64>(),
            any::<u8>(),
        ),
    )
        .prop_map(
            |(
                state,
                (homed, laser_on, axes, detection, drivers_enabled, estop_open),
                (sent, flagged, remeasured, sanity_loaded, last_fault, laser_inhibited, up, held),
            )| Status {
                state,
                homed,
                laser_on,
                drivers_enabled,
                estop_open,
                axes,
                detection,
                samples_sent: sent,
                samples_flagged: flagged,
                samples_remeasured: remeasured,
                sanity_loaded,
                last_fault,
                laser_inhibited,
                uptime_us: up,
                requests_held: held,
            },
        )
}

pub fn identity() -> impl Strategy<Value = Identity> {
    (
        "[ -~]{0,16}",
        "[ -~]{0,32}",
        "[0-9A-F]{0,24}",
        any::<u16>(),
        any::<bool>(),
        proptest::array::uniform4(any_f32()),
    )
        .prop_map(|(fw, board, serial, pv, simulated, gains)| Identity {
            protocol_version: pv,
            firmware_version: heapless::String::try_from(fw.as_str()).unwrap_or_default(),
            board: heapless::String::try_from(board.as_str()).unwrap_or_default(),
            serial: heapless::String::try_from(serial.as_str()).unwrap_or_default(),
            simulated,
            capabilities: Capabilities {
                axes: 3,
                gain_ranges: 4,
                adc_bits: 12,
                max_scan_incidences: 8,
                gains_v_per_a: gains,
            },
        })
}

pub fn scan_event() -> impl Strategy<Value = ScanEvent> {
    prop_oneof![
        sample().prop_map(ScanEvent::Sample),
        swept_sample().prop_map(ScanEvent::SweptSample),
        (any::<u32>(), any::<u32>(), any::<u32>()).prop_map(|(index, order, samples)| ScanEvent::Swept { index, order, samples }),
        (any::<u32>(), any::<u32>(), fault()).prop_map(|(index, order, reason)| ScanEvent::Skipped { index, order, reason }),
        (any::<u32>(), any::<u32>(), any::<u32>()).prop_map(|(run, measured, skipped)| ScanEvent::Finished { run, measured, skipped }),
        (any::<u32>(), any::<u32>(), fault()).prop_map(|(run, next_order, reason)| ScanEvent::Stopped { run, next_order, reason }),
    ]
}

pub fn home_request() -> impl Strategy<Value = HomeRequest> {
    (any::<bool>(), any::<bool>(), any::<bool>()).prop_map(|(rotation, cradle, arm)| HomeRequest { rotation, cradle, arm })
}

pub fn measure_request() -> impl Strategy<Value = MeasureRequest> {
    proptest::option::of(geometry()).prop_map(|at| MeasureRequest { at })
}

pub fn move_report() -> impl Strategy<Value = MoveReport> {
    (geometry(), axis_angles(), any_f32()).prop_map(|(reached, axes, duration_s)| MoveReport { reached, axes, duration_s })
}
