//! One scan of a grid into a fresh sample file in a directory, read back:
//! the step every end-to-end test on the simulated head shares.

use gonio_acquire::operator::Operator;
use gonio_acquire::scan;
use gonio_acquire::scan_order::visit_order;
use gonio_acquire::session::{Session, Setup};
use gonio_acquire::target::Target;
use gonio_firmware::motion::PARK;
use gonio_scan_dir::run::ScanOutcome;
use gonio_scan_dir::samples::{self, Row, SampleWriter};
use gonio_shared::{DetectionSettings, ScanSpec};
use std::path::Path;
use std::sync::Arc;

/// Scans `spec` with a hidden progress bar and no drift monitor; returns the
/// outcome and the rows stored in `dir`. Panics on any error: for tests.
pub async fn scan_and_read(session: &mut Session, spec: &ScanSpec, dir: &Path) -> (ScanOutcome, Vec<Row>) {
    let mut out = SampleWriter::create(dir).unwrap();
    let progress = scan::progress::Progress::new(Operator::Silent, vec![0.0], spec.first_order, "points", Default::default());
    let order = visit_order(session.head().config(), spec, PARK).collect();
    let outcome = scan::drive(session, spec, order, &mut out, &progress, None).await.unwrap();
    let rows = samples::read(&out.finish().unwrap()).unwrap();
    (outcome, rows)
}

/// A connected, prepared (homed) session, as `gonio scan` opens it.
pub async fn session(target: Arc<dyn Target>) -> Session {
    let setup = Setup {
        settings: DetectionSettings::default(),
        learn_at: None,
        learning_periods: 0,
    };
    let mut s = Session::connect(target, setup, Operator::Silent).await.unwrap();
    s.start().await.unwrap();
    s
}
