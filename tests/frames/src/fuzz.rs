//! The bodies of the fuzz targets (`fuzz`, cargo-fuzz): each takes
//! arbitrary bytes and panics only on a real defect. They live here so that
//! `cargo test` runs every committed seed through them on stable Rust
//! (tests/fuzz_corpus.rs), and `fuzz-seeds` writes those seeds.

use crate::{request, sealed};
use gonio_analysis::formats::{alta, brdf_csv};
use gonio_firmware::dispatch;
use gonio_shared::icd::{
    AbortEndpoint, ContinueEndpoint, DetectionEndpoint, HomeEndpoint, HomeRequest, IdentifyEndpoint, LearnEndpoint, MeasureEndpoint,
    MeasureRequest, MechanicsEndpoint, MoveEndpoint, PauseEndpoint, SafetyEndpoint, SanityEndpoint, ScanEndpoint, StatusEndpoint,
    VisitEndpoint,
};
use gonio_shared::wire::check;
use gonio_shared::wire::framing::{self, Decoder};
use gonio_shared::{
    AngleRange, DetectionSettings, Geometry, LearnRequest, SafetySettings, SanityConfig, SanityKind, SanityModel, ScanSpec,
};
use gonio_sim::{FrameHead, SimConfig};

/// The head's receive path on a byte stream: COBS frames, their check, and
/// the request decoder; the decoder also sees the raw bytes, since random
/// input rarely carries a valid CRC.
pub fn frame_decode(data: &[u8]) {
    let _ = dispatch::decode(data);
    let mut d = Decoder::new();
    d.feed(data, |f| {
        if f.len() > framing::MAX_FRAME {
            panic!("the decoder passed on a frame of {} bytes", f.len());
        }
        if let Some(frame) = check::open(f) {
            let _ = dispatch::decode(frame);
        }
    });
}

/// Splits fuzz bytes into frames: a length byte, then that many bytes.
fn frames(data: &[u8]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut rest = data;
    while let Some((&n, tail)) = rest.split_first() {
        let n = (n as usize).min(tail.len());
        out.push(tail[..n].to_vec());
        rest = &tail[n..];
    }
    out
}

/// The firmware's command dispatch on the simulated head: the frames (each
/// sealed, so they reach the dispatcher) are served as one link session.
/// Whatever they asked, once the link is gone the laser is off and every
/// driver disabled.
pub fn dispatch(data: &[u8]) {
    let mut head = FrameHead::new(&SimConfig::default());
    head.serve(frames(data).into_iter().map(sealed));
    let w = head.world();
    assert!(!w.laser, "laser left on after the link closed");
    assert!(
        w.enable_n.iter().all(|&off| off),
        "a motor driver left enabled after the link closed"
    );
}

/// The ALTA reader; what it accepts, the writer writes back to the same values.
pub fn alta_reader(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(d) = alta::parse(text) else { return };
    let again = alta::parse(&alta::write(&d)).expect("written ALTA reads back");
    assert_eq!(again.observations.len(), d.observations.len());
    for (a, b) in d.observations.iter().zip(&again.observations) {
        assert_eq!(a.value.to_bits(), b.value.to_bits(), "value changed in the round trip");
    }
}

/// The BRDF CSV reader: errors, never panics; what it accepts is finite.
pub fn csv_reader(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(d) = brdf_csv::parse(text) {
        assert!(d.observations.iter().all(|o| o.value.is_finite() && o.theta_i.is_finite()));
    }
}

/// Seed inputs per target: every request once (valid and invalid values), a
/// session that homes and scans, ALTA and CSV files of each kind.
pub fn seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let scan = ScanSpec {
        theta_o: AngleRange::new(0.0, 30.0, 10.0),
        dphi: AngleRange::new(0.0, 20.0, 10.0),
        ..ScanSpec::belcour()
    };
    let sanity = SanityConfig {
        model: SanityModel::from_params(SanityKind::Lambert, &[0.5]).expect("a Lambertian"),
        current_a_per_sr_inv: 1e-6,
        splitter_factor: 0.21,
        rel_tol: 0.02,
        abs_tol_v: 1e-4,
        k_noise: 3.0,
        remeasure: true,
    };
    let requests: Vec<(&str, Vec<u8>)> = vec![
        ("identify", request::<IdentifyEndpoint>(&())),
        ("status", request::<StatusEndpoint>(&())),
        ("mechanics", request::<MechanicsEndpoint>(&())),
        ("home", request::<HomeEndpoint>(&HomeRequest::ALL)),
        ("move", request::<MoveEndpoint>(&Geometry::new(30.0, 20.0, 90.0))),
        ("move-nan", request::<MoveEndpoint>(&Geometry::new(f32::NAN, 20.0, 90.0))),
        (
            "measure",
            request::<MeasureEndpoint>(&MeasureRequest {
                at: Some(Geometry::new(30.0, 20.0, 90.0)),
            }),
        ),
        ("scan", request::<ScanEndpoint>(&scan)),
        (
            "sweep-scan",
            request::<ScanEndpoint>(&ScanSpec {
                sweep: Some(gonio_shared::SweepScan {
                    speed_dps: 30.0,
                    periods_per_sample: 4,
                    lobe: Some(gonio_shared::SweepLobe {
                        width_deg: 2.0,
                        extent_fraction: 0.25,
                    }),
                }),
                ..scan.clone()
            }),
        ),
        (
            "visits",
            request::<VisitEndpoint>(&gonio_shared::VisitChunk {
                run: 1,
                first_order: 0,
                indices: (0..gonio_shared::VISIT_CHUNK as u32).collect(),
            }),
        ),
        ("abort", request::<AbortEndpoint>(&())),
        ("pause", request::<PauseEndpoint>(&())),
        ("continue", request::<ContinueEndpoint>(&())),
        ("detection", request::<DetectionEndpoint>(&DetectionSettings::default())),
        ("sanity", request::<SanityEndpoint>(&sanity)),
        ("learn", request::<LearnEndpoint>(&LearnRequest { periods: 23 })),
        (
            "safety",
            request::<SafetyEndpoint>(&SafetySettings {
                host_timeout_s: 5.0,
                ..SafetySettings::default()
            }),
        ),
    ];
    let mut out = Vec::new();
    for (name, f) in &requests {
        out.push(("frame_decode", name.to_string(), f.clone()));
        let mut cobs = vec![0u8; framing::MAX_ENCODED];
        let n = framing::encode(&sealed(f.clone()), &mut cobs).unwrap_or(0);
        cobs.truncate(n);
        out.push(("frame_decode", format!("{name}-cobs"), cobs));
    }
    let session = |names: &[&str]| -> Vec<u8> {
        let mut s = Vec::new();
        for n in names {
            let f = &requests.iter().find(|(k, _)| k == n).expect("a seed request").1;
            s.push(f.len() as u8);
            s.extend_from_slice(f);
        }
        s
    };
    out.push((
        "dispatch",
        "home-move-measure".into(),
        session(&["identify", "home", "move", "measure", "status"]),
    ));
    out.push((
        "dispatch",
        "home-scan-abort".into(),
        session(&["home", "detection", "scan", "status", "abort"]),
    ));
    out.push((
        "dispatch",
        "scan-pause-continue".into(),
        session(&["home", "scan", "pause", "status", "continue", "pause", "abort"]),
    ));
    out.push((
        "dispatch",
        "learn-sanity".into(),
        session(&["home", "move", "learn", "sanity", "measure"]),
    ));
    out.push((
        "dispatch",
        "refused".into(),
        session(&["move-nan", "measure", "scan", "home", "move-nan"]),
    ));
    out.push((
        "alta_reader",
        "tl-tv-proj-dphi".into(),
        b"#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n#VS 0\n0.5 0.4 0.1 1.25\n0.5 0.5 3.0 2.0e-1\n".to_vec(),
    ));
    out.push((
        "alta_reader",
        "spherical".into(),
        b"# from gonio\n#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n#VS 0\n0.5 0 0.4 3.1 0.8\n"
            .to_vec(),
    ));
    out.push((
        "alta_reader",
        "intervals".into(),
        b"#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n#VS 2\n0.5 0.4 0.1 1.25 0.1 0.2\n0.5 0.5 3.0 2.0e-1 0 0.05\n"
            .to_vec(),
    ));
    out.push((
        "alta_reader",
        "interval-ends".into(),
        format!(
            "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#VS 2\n# {}\n0.5 0.4 0.1 1.25 1.2 1.3\n",
            alta::ENDS_NOTE
        )
        .into_bytes(),
    ));
    out.push((
        "csv_reader",
        "brdf-sr".into(),
        b"theta_i_deg,theta_o_deg,dphi_deg,brdf_sr,brdf_sigma_sr,usable\n30,20,90,0.12,0.001,true\n30,30,0,40.5,0.2,false\n".to_vec(),
    ));
    out.push((
        "csv_reader",
        "brdf-cos".into(),
        b"theta_i_deg,theta_o_deg,dphi_deg,brdf_cos_sr\n15,0,0,0.3\n".to_vec(),
    ));
    out
}

/// The target function of a name.
pub fn target(name: &str) -> Option<fn(&[u8])> {
    Some(match name {
        "frame_decode" => frame_decode,
        "dispatch" => dispatch,
        "alta_reader" => alta_reader,
        "csv_reader" => csv_reader,
        _ => return None,
    })
}
