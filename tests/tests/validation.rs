//! Commands are validated at the boundary. Random sequences of
//! commands, valid ones among them and many with NaN, infinite or
//! out-of-range fields, are served to the firmware on the simulated head in
//! one session; after every refused command the stages are where they were,
//! the laser was not switched on and no driver was enabled.

use gonio_frames::{refusal, replies, send};
use gonio_shared::icd::{
    AbortEndpoint, DetectionEndpoint, HomeEndpoint, HomeRequest, LearnEndpoint, MeasureEndpoint, MeasureRequest, MoveEndpoint,
    SafetyEndpoint, SanityEndpoint, ScanEndpoint, StatusEndpoint,
};
use gonio_shared::{Fault, Geometry, LearnRequest, SafetySettings};
use gonio_sim::{FrameHead, Sent, SimConfig};
use gonio_tests::strategies::{any_f32, detection_settings, geometry, sanity_config, scan_spec};
use proptest::prelude::*;

/// A geometry the head can usually reach.
fn plausible() -> impl Strategy<Value = Geometry> {
    (5.0f32..70.0, 0.0f32..85.0, -180.0f32..180.0).prop_map(|(a, b, c)| Geometry::new(a, b, c))
}

/// One command frame.
fn command() -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        1 => Just(send::<HomeEndpoint>(&HomeRequest::ALL)),
        3 => prop_oneof![geometry(), plausible()].prop_map(|g| send::<MoveEndpoint>(&g)),
        2 => proptest::option::of(prop_oneof![geometry(), plausible()])
            .prop_map(|at| send::<MeasureEndpoint>(&MeasureRequest { at })),
        // Only scans the head must refuse: an accepted one moves between
        // later replies, on purpose.
        2 => scan_spec().prop_filter("an invalid scan", |s| s.validate().is_err()).prop_map(|s| send::<ScanEndpoint>(&s)),
        2 => detection_settings().prop_map(|d| send::<DetectionEndpoint>(&d)),
        1 => sanity_config().prop_map(|c| send::<SanityEndpoint>(&c)),
        1 => any::<u16>().prop_map(|periods| send::<LearnEndpoint>(&LearnRequest { periods })),
        1 => any_f32().prop_map(|t| send::<SafetyEndpoint>(&SafetySettings {
            host_timeout_s: t,
            ..SafetySettings::default()
        })),
        1 => Just(send::<StatusEndpoint>(&())),
        1 => Just(send::<AbortEndpoint>(&())),
    ]
}

/// Whether `sent` answers with a `Reply` (so can be refused): status and
/// abort answer with the head's status. A status poll is answered as it
/// arrives, during an operation too, so answers are not in the commands'
/// order: they are told apart by their keys.
fn is_reply(sent: &Sent) -> bool {
    let one = std::slice::from_ref(sent);
    replies::<StatusEndpoint>(one).is_empty() && replies::<AbortEndpoint>(one).is_empty()
}

/// Refusals: the command was checked and dropped before acting.
fn refused(f: Fault) -> bool {
    matches!(
        f,
        Fault::InvalidValue(_) | Fault::Unreachable(_) | Fault::NotHomed | Fault::Busy | Fault::NotLearned
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn nothing_moves_and_the_laser_stays_dark_after_a_refused_command(cmds in proptest::collection::vec(command(), 1..14)) {
        let mut head = FrameHead::new(&SimConfig::default());
        let before = {
            let w = head.world();
            Sent { frame: Vec::new(), laser: w.laser, drivers_enabled: w.enable_n.iter().any(|&off| !off), steps: w.steps, laser_ons: w.laser_ons, t_s: w.t_s }
        };
        let sent = head.serve(cmds.iter().cloned());
        // One answer per command (no scan runs, so no events).
        prop_assert_eq!(sent.len(), cmds.len());
        let mut prev = &before;
        let mut refusals = 0;
        for reply in &sent {
            if let Some(f) = refusal(reply).filter(|&f| is_reply(reply) && refused(f)) {
                refusals += 1;
                prop_assert_eq!(reply.steps, prev.steps, "{} moved the stages", f);
                prop_assert_eq!(reply.laser_ons, prev.laser_ons, "{} switched the laser on", f);
                prop_assert!(!reply.laser || prev.laser, "{} left the laser on", f);
                prop_assert!(!reply.drivers_enabled || prev.drivers_enabled, "{} enabled a driver", f);
            }
            prev = reply;
        }
        // Most sequences carry refusals; the property is not vacuous.
        prop_assume!(refusals > 0);
    }
}
