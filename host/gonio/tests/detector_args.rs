//! The detector's options as the command line gives them, checked into
//! what the scan's record keeps.

use clap::Parser;
use gonio::cli::detector::DetectorArgs;
use gonio_shared::Reference;

#[derive(Parser)]
struct Detector {
    #[command(flatten)]
    detector: DetectorArgs,
}

#[test]
fn a_negative_integration_time_gets_a_sentence() {
    for t in ["-1", "0", "11"] {
        let d = Detector::try_parse_from(["detector", "--integration-s", t]).unwrap();
        let e = d.detector.checked().unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "--integration-s {t} s: a point's integration time must be longer than 0 s and at most 10 s"
            )),
            "{e}"
        );
    }
}

#[test]
fn the_demo_options_check() {
    let c = DetectorArgs::demo().checked().unwrap();
    assert_eq!(c.reference, Reference::Matched);
    assert!(c.learn_at.is_some());
}
