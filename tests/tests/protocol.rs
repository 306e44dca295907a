//! The protocol: every message round-trips through postcard; the head's frame
//! decoder refuses random, truncated and unknown frames without panicking; the
//! largest messages fit the head's frame buffer; requests the head has no
//! room to keep during an operation are refused at once.

use gonio_firmware::dispatch::{decode, encode, Command, DecodeError};
use gonio_shared::icd::*;
use gonio_shared::wire::framing::MAX_FRAME;
use gonio_shared::*;
use gonio_tests::strategies::*;
use postcard_rpc::header::{VarHeader, VarKey, VarKeyKind, VarSeq};
use postcard_rpc::standard_icd::WireError;
use postcard_rpc::{Endpoint, Key, Topic};
use proptest::prelude::*;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Encode → decode → encode gives the same bytes (NaN-proof equality).
fn roundtrip<T: Serialize + DeserializeOwned>(msg: &T) -> Result<(), TestCaseError> {
    let bytes = postcard::to_stdvec(msg).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let back: T = postcard::from_bytes(&bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert_eq!(postcard::to_stdvec(&back).unwrap(), bytes);
    Ok(())
}

/// Every strict prefix of a message's encoding fails to decode, cleanly.
fn truncations_fail<T: Serialize + DeserializeOwned>(msg: &T) -> Result<(), TestCaseError> {
    let bytes = postcard::to_stdvec(msg).unwrap();
    for n in 0..bytes.len() {
        prop_assert!(postcard::from_bytes::<T>(&bytes[..n]).is_err(), "prefix of {} bytes decoded", n);
    }
    Ok(())
}

fn frame<E: Endpoint>(req: &E::Request) -> Vec<u8>
where
    E::Request: Serialize,
{
    let mut buf = vec![0u8; 1024];
    let n = encode(E::REQ_KEY, VarKeyKind::Key8, VarSeq::Seq4(7), req, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn geometry_faults_and_settings_roundtrip(g in geometry(), a in axis_angles(), f in fault(), d in detection_settings()) {
        roundtrip(&g)?; roundtrip(&a)?; roundtrip(&f)?; roundtrip(&d)?;
    }

    #[test]
    fn samples_and_scan_events_roundtrip(s in sample(), ev in scan_event(), f in fault()) {
        roundtrip(&s)?; roundtrip(&ev)?;
        roundtrip::<Reply<Sample>>(&Ok(s))?; roundtrip::<Reply<Sample>>(&Err(f))?;
    }

    #[test]
    fn scans_and_sanity_models_roundtrip(spec in scan_spec(), sc in sanity_config()) {
        roundtrip(&spec)?; roundtrip(&sc)?;
    }

    #[test]
    fn status_and_identity_roundtrip(st in status(), id in identity()) {
        roundtrip(&st)?; roundtrip(&id)?;
    }

    #[test]
    fn requests_and_reports_roundtrip(h in home_request(), m in measure_request(), mr in move_report()) {
        roundtrip(&h)?; roundtrip(&m)?; roundtrip(&mr)?;
    }

    #[test]
    fn truncated_messages_are_errors(st in status(), id in identity(), ev in scan_event(), spec in scan_spec()) {
        truncations_fail(&st)?; truncations_fail(&id)?; truncations_fail(&ev)?; truncations_fail(&spec)?;
    }

    #[test]
    fn random_bytes_never_panic_the_decoders(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = decode(&bytes);
        let _ = postcard::from_bytes::<ScanEvent>(&bytes);
        let _ = postcard::from_bytes::<Status>(&bytes);
        let _ = postcard::from_bytes::<Identity>(&bytes);
        let mut d = gonio_shared::wire::framing::Decoder::new();
        d.feed(&bytes, |_| {});
    }

    #[test]
    fn requests_decode_to_their_command(g in geometry(), spec in scan_spec(), d in detection_settings(), sc in sanity_config()) {
        prop_assert!(matches!(decode(&frame::<MoveEndpoint>(&g)), Ok((_, Command::Move(x))) if postcard::to_stdvec(&x).unwrap() == postcard::to_stdvec(&g).unwrap()));
        prop_assert!(matches!(decode(&frame::<ScanEndpoint>(&spec)), Ok((_, Command::Scan(_)))));
        prop_assert!(matches!(decode(&frame::<DetectionEndpoint>(&d)), Ok((_, Command::Detection(_)))));
        prop_assert!(matches!(decode(&frame::<SanityEndpoint>(&sc)), Ok((_, Command::Sanity(_)))));
    }

    #[test]
    fn truncated_request_bodies_are_refused(spec in scan_spec()) {
        let f = frame::<ScanEndpoint>(&spec);
        // Header is 1 discriminant + 8 key + 4 sequence bytes.
        for n in 13..f.len() {
            prop_assert!(matches!(decode(&f[..n]), Err(DecodeError::Wire(_, WireError::DeserFailed))));
        }
        for n in 0..13 {
            prop_assert_eq!(decode(&f[..n]).unwrap_err(), DecodeError::NoHeader);
        }
    }
}

#[test]
fn every_request_is_recognised_at_every_key_width() {
    for kind in [VarKeyKind::Key1, VarKeyKind::Key2, VarKeyKind::Key4, VarKeyKind::Key8] {
        let mut buf = [0u8; 64];
        let n = encode(IdentifyEndpoint::REQ_KEY, kind, VarSeq::Seq1(3), &(), &mut buf).unwrap();
        let (hdr, cmd) = decode(&buf[..n]).unwrap();
        assert_eq!(cmd, Command::Identify(()));
        assert_eq!(hdr.seq_no, VarSeq::Seq1(3));
    }
    let (_, cmd) = decode(&frame::<HomeEndpoint>(&HomeRequest::ALL)).unwrap();
    assert_eq!(cmd, Command::Home(HomeRequest::ALL));
    assert_eq!(decode(&frame::<AbortEndpoint>(&())).unwrap().1, Command::Abort(()));
    assert_eq!(decode(&frame::<StatusEndpoint>(&())).unwrap().1, Command::Status(()));
}

/// Every endpoint of the ICD is a command the head decodes (both come from
/// the one table in `icd.rs`): its key is known to the decoder (an empty
/// body may not decode, but it is never an unknown key).
#[test]
fn every_endpoint_of_the_icd_is_decoded() {
    // The list also holds postcard-rpc's own standard endpoints (ping, ...).
    let ours = ENDPOINT_LIST.endpoints.iter().filter(|(path, ..)| path.starts_with("gonio/"));
    assert!(ours.clone().count() > 1, "no gonio/ endpoint in the list");
    for (path, req_key, _) in ours {
        let mut buf = [0u8; 64];
        let n = encode(*req_key, VarKeyKind::Key8, VarSeq::Seq1(1), &(), &mut buf).unwrap();
        let got = decode(&buf[..n]);
        assert!(
            !matches!(got, Err(DecodeError::Wire(_, WireError::UnknownKey))),
            "{path}: the head does not decode it"
        );
    }
}

#[test]
fn unknown_keys_are_answered_as_such() {
    let mut buf = [0u8; 64];
    let bogus = Key::for_path::<u32>("gonio/not-an-endpoint");
    let n = encode(bogus, VarKeyKind::Key8, VarSeq::Seq4(9), &1u32, &mut buf).unwrap();
    match decode(&buf[..n]) {
        Err(DecodeError::Wire(hdr, WireError::UnknownKey)) => {
            assert_eq!(hdr.seq_no, VarSeq::Seq4(9));
            assert_eq!(hdr.key, VarKey::Key8(bogus));
        }
        other => panic!("expected UnknownKey, got {other:?}"),
    }
    // A request whose schema changed has a different key: also unknown.
    let changed = Key::for_path::<(f32, f32)>(MoveEndpoint::PATH);
    let n = encode(changed, VarKeyKind::Key8, VarSeq::Seq4(1), &(1.0f32, 2.0f32), &mut buf).unwrap();
    assert!(matches!(decode(&buf[..n]), Err(DecodeError::Wire(_, WireError::UnknownKey))));
    let _ = VarHeader::take_from_slice(&buf[..n]).unwrap();
}

#[test]
fn largest_messages_fit_the_frame_buffer() {
    let s = Sample {
        seq: u32::MAX,
        scan: Some(gonio_shared::sample::ScanPosition {
            index: u32::MAX,
            order: u32::MAX,
        }),
        timestamp_us: u64::MAX,
        target: Geometry::new(1.0, 2.0, 3.0),
        reached: Geometry::new(1.0, 2.0, 3.0),
        axes: AxisAngles::default(),
        signal: Signal {
            in_phase_v: 1.0,
            quadrature_v: 1.0,
            amplitude_v: 1.0,
            magnitude_v: 1.0,
            phase_deg: 1.0,
            noise_v: 1.0,
            gain_v_per_a: 1.0,
            gain_index: u8::MAX,
            periods: u16::MAX,
            flags: SampleFlags::from_bits_retain(u16::MAX),
        },
    };
    // The frame check takes the last bytes of the buffer.
    let mut buf = [0u8; MAX_FRAME - gonio_shared::wire::check::LEN];
    let seq = VarSeq::Seq4(u32::MAX);
    assert!(encode(ScanEventTopic::TOPIC_KEY, VarKeyKind::Key8, seq, &ScanEvent::Sample(s), &mut buf).is_some());
    assert!(encode(MeasureEndpoint::RESP_KEY, VarKeyKind::Key8, seq, &Ok::<_, Fault>(s), &mut buf).is_some());
    let swept = SweptSample {
        seq: s.seq,
        scan: s.scan,
        start_us: s.timestamp_us,
        duration_s: 1.0,
        axes_from: AxisAngles::default(),
        axes_to: AxisAngles::default(),
        signal: s.signal,
    };
    assert!(encode(
        ScanEventTopic::TOPIC_KEY,
        VarKeyKind::Key8,
        seq,
        &ScanEvent::SweptSample(swept),
        &mut buf
    )
    .is_some());
    let id = Identity {
        protocol_version: u16::MAX,
        firmware_version: heapless::String::try_from("x".repeat(16).as_str()).unwrap(),
        board: heapless::String::try_from("x".repeat(32).as_str()).unwrap(),
        serial: heapless::String::try_from("x".repeat(24).as_str()).unwrap(),
        simulated: true,
        capabilities: Capabilities {
            axes: 3,
            gain_ranges: 4,
            adc_bits: 12,
            max_scan_incidences: 8,
            gains_v_per_a: [1.0; 4],
        },
    };
    assert!(encode(IdentifyEndpoint::RESP_KEY, VarKeyKind::Key8, seq, &id, &mut buf).is_some());
    let st = Status {
        state: HeadState::Scanning {
            next_order: u32::MAX,
            total: u32::MAX,
        },
        homed: true,
        laser_on: true,
        drivers_enabled: true,
        estop_open: true,
        axes: AxisAngles::default(),
        detection: DetectionSettings::default(),
        samples_sent: u32::MAX,
        samples_flagged: u32::MAX,
        samples_remeasured: u32::MAX,
        sanity_loaded: true,
        last_fault: Some(Fault::HomeSwitchNotFound(Axis::Arm)),
        laser_inhibited: Some(Fault::Crystal {
            measured_khz: u32::MAX,
            expected_khz: u32::MAX,
        }),
        uptime_us: u64::MAX,
        requests_held: u8::MAX,
    };
    assert!(encode(StatusEndpoint::RESP_KEY, VarKeyKind::Key8, seq, &st, &mut buf).is_some());
    // And the largest request the host can send.
    let mut spec = ScanSpec::belcour();
    while spec.theta_i_deg.push(1.0).is_ok() {}
    spec.first_order = u32::MAX;
    spec.sweep = Some(gonio_shared::SweepScan {
        speed_dps: 1.0,
        periods_per_sample: u16::MAX,
        lobe: Some(gonio_shared::SweepLobe {
            width_deg: f32::MAX,
            extent_fraction: f32::MAX,
        }),
    });
    assert!(encode(ScanEndpoint::REQ_KEY, VarKeyKind::Key8, seq, &spec, &mut buf).is_some());
}

/// During an operation the head keeps 16 requests for when it ends; one
/// more is refused at once with `FailedToSpawn`, not dropped, so the host
/// learns of it without waiting for its timeout. Homing from power-up takes
/// seconds; the identity requests come behind it.
#[test]
fn requests_beyond_those_kept_during_an_operation_are_refused_at_once() {
    use gonio_frames::{replies, send, wire_errors};
    let mut head = gonio_sim::FrameHead::new(&gonio_sim::SimConfig::default());
    let extra = 4;
    let frames = std::iter::once(send::<HomeEndpoint>(&HomeRequest::ALL))
        .chain((0..16 + extra).map(|_| send::<IdentifyEndpoint>(&())))
        .collect::<Vec<_>>();
    let sent = head.serve(frames);
    let refused = wire_errors(&sent);
    assert_eq!(refused.len(), extra, "{refused:?}");
    assert!(refused.iter().all(|e| matches!(e, WireError::FailedToSpawn)), "{refused:?}");
    assert_eq!(replies::<IdentifyEndpoint>(&sent).len(), 16);
    // Refused while homing: before the homing's reply.
    let homed = sent
        .iter()
        .position(|s| !replies::<HomeEndpoint>(std::slice::from_ref(s)).is_empty());
    let last_refusal = sent.iter().rposition(|s| !wire_errors(std::slice::from_ref(s)).is_empty());
    assert!(
        last_refusal < homed && homed.is_some(),
        "refused at {last_refusal:?}, homed at {homed:?}"
    );
}
