//! One scan of a grid into a fresh sample file in a directory, read back:
//! the step every end-to-end test on the simulated head shares.

use gonio_host::operator::Operator;
use gonio_host::samples_csv::{self, Row, SampleWriter};
use gonio_host::scan::{self, ScanOutcome};
use gonio_host::session::Session;
use gonio_shared::ScanSpec;
use std::path::Path;

/// Scans `spec` with a hidden progress bar and no drift monitor; returns the
/// outcome and the rows stored in `dir`. Panics on any error: for tests.
pub async fn scan_and_read(session: &mut Session, spec: &ScanSpec, dir: &Path) -> (ScanOutcome, Vec<Row>) {
    let mut out = SampleWriter::create(dir).unwrap();
    let outcome = scan::run(session, spec, &mut out, &Operator::Silent.bar(0, "scanning", "points"), None)
        .await
        .unwrap();
    let rows = samples_csv::read(&out.finish().unwrap()).unwrap();
    (outcome, rows)
}
