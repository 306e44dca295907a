//! Sweep scans through the host, on the simulated head: every row the head
//! can sweep is stored once and whole (consecutive samples, as many as the
//! head says it sent), at its incidence, from the retro direction's side out
//! to its θo stop or back; lost,
//! duplicated and reordered frames and a pulled cable are recovered by
//! sweeping the row again.

use gonio_firmware::config::REFERENCE;
use gonio_firmware::sweep;
use gonio_host::cli::simulated::Simulated;
use gonio_host::samples_csv::Row;
use gonio_host::scan::ScanOutcome;
use gonio_shared::{AngleRange, ScanSpec, SweepRow, SweepScan, Visit};
use gonio_sim::faults::Faults;
use gonio_sim::SimConfig;
use gonio_tests::scanning::{scan_and_read, session};
use std::collections::BTreeMap;
use std::sync::Arc;

/// Five rows at θi = 30°, out to θo = 60°.
fn rows() -> ScanSpec {
    ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[30.0]).unwrap(),
        theta_o: AngleRange::new(0.0, 60.0, 3.0),
        dphi: AngleRange::new(-180.0, 180.0, 90.0),
        first_order: 0,
        sweep: Some(SweepScan {
            speed_dps: 20.0,
            periods_per_sample: 8,
        }),
    }
}

/// The rows (visit positions) the head can sweep.
fn sweepable(spec: &ScanSpec) -> Vec<u32> {
    (0..spec.len())
        .filter(|&o| sweep::row_ends(&REFERENCE, &row(spec, o)).is_ok())
        .collect()
}

/// The row visited at position `o`.
fn row(spec: &ScanSpec, o: u32) -> SweepRow {
    match spec.index_at_order(o).and_then(|i| spec.visit(i, o)) {
        Some(Visit::Row(r)) => r,
        other => panic!("position {o} is not a row: {other:?}"),
    }
}

async fn scan(sim: SimConfig) -> (ScanOutcome, BTreeMap<u32, Vec<Row>>) {
    let mut session = session(Arc::new(Simulated(sim))).await;
    let dir = tempfile::tempdir().unwrap();
    let (outcome, stored) = scan_and_read(&mut session, &rows(), dir.path()).await;
    session.close().await;
    let mut by_row: BTreeMap<u32, Vec<Row>> = BTreeMap::new();
    for r in stored {
        by_row.entry(r.order.expect("a scan position")).or_default().push(r);
    }
    (outcome, by_row)
}

/// Every row stored is whole: consecutive samples in time and `seq`, each
/// swept (an extent), all at the row's incidence, from the retro side (the
/// arm just beyond its blind zone) out to the row's θo stop, or back.
fn check_whole(spec: &ScanSpec, by_row: &BTreeMap<u32, Vec<Row>>) {
    for (&o, samples) in by_row {
        assert!(samples.len() > 20, "row {o}: {} samples", samples.len());
        for w in samples.windows(2) {
            assert_eq!(w[0].seq + 1, w[1].seq, "row {o} is not whole");
            assert!(w[0].timestamp_s < w[1].timestamp_s);
        }
        let r = row(spec, o);
        let (near, far) = if r.outward {
            (&samples[0], &samples[samples.len() - 1])
        } else {
            (&samples[samples.len() - 1], &samples[0])
        };
        assert!(near.psi_deg > 5.0 && near.psi_deg < 7.0, "row {o} begins at {near:?}");
        assert!((far.theta_o_deg - r.theta_o_stop_deg).abs() < 1.0, "row {o} ends at {far:?}");
        for s in samples {
            assert!((s.theta_i_deg - r.theta_i_deg).abs() < 0.01, "row {o} left its incidence: {s:?}");
            let extent = s.extent_deg.expect("a swept sample's extent");
            assert!(extent > 0.0 && extent < 2.0, "row {o}: extent {extent}° of {s:?}");
        }
    }
}

#[tokio::test]
async fn a_sweep_scan_stores_every_row_it_can_sweep_once_and_whole() {
    let spec = rows();
    let (outcome, by_row) = scan(SimConfig::default()).await;
    let rows: Vec<u32> = by_row.keys().copied().collect();
    let expected = sweepable(&spec);
    assert!(expected.len() >= 3, "{expected:?}");
    assert_eq!(rows, expected);
    assert_eq!(outcome.measured as usize, rows.len());
    assert_eq!(outcome.measured + outcome.skipped, spec.len());
    assert_eq!(outcome.swept_samples as usize, by_row.values().map(Vec::len).sum::<usize>());
    check_whole(&spec, &by_row);
}

#[tokio::test]
async fn lost_duplicated_and_reordered_frames_and_a_pulled_cable_cost_a_row_swept_again() {
    // Frames the head sends: answers, then the scan's events (some 90 per
    // row); faults in the first rows, the cable pulled in the third.
    let sim = SimConfig {
        faults: Faults::parse("drop@40,duplicate@140,reorder@230,disconnect@330").unwrap(),
        ..SimConfig::default()
    };
    let spec = rows();
    let (outcome, by_row) = scan(sim).await;
    assert_eq!(by_row.keys().copied().collect::<Vec<_>>(), sweepable(&spec));
    check_whole(&spec, &by_row);
    let recovered: u32 = outcome.recoveries.values().sum();
    assert!(recovered >= 3, "{:?}", outcome.recoveries);
    assert!(
        outcome.recoveries.keys().any(|k| k.contains("link lost")),
        "{:?}",
        outcome.recoveries
    );
}
