//! Sweep scans through the host, on the simulated head: every row the head
//! can sweep is stored once and whole (consecutive samples, as many as the
//! head says it sent), at its incidence, from the retro direction's side out
//! to its θo stop or back, and each incidence's retro point once; lost,
//! duplicated and reordered frames and a pulled cable are recovered by
//! sweeping the row again.

use gonio::cli::in_process::Simulated;
use gonio_brdf::{Material, Specimen};
use gonio_firmware::config::REFERENCE;
use gonio_firmware::motion::{self, executor::QUEUE};
use gonio_firmware::sweep;
use gonio_scan_dir::run::ScanOutcome;
use gonio_scan_dir::samples::Row;
use gonio_shared::{AngleRange, SampleFlags, ScanSpec, SweepLobe, SweepRow, SweepScan, Visit};
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
            lobe: None,
        }),
        patterns: None,
    }
}

/// [`rows`] at `speed_dps`, slowed down for a lobe `width_deg` wide, a
/// sample spanning at most a quarter of it.
fn slowed(width_deg: f32, speed_dps: f32) -> ScanSpec {
    let lobe = SweepLobe {
        width_deg,
        extent_fraction: 0.25,
    };
    ScanSpec {
        sweep: rows().sweep.map(|s| SweepScan {
            lobe: Some(lobe),
            speed_dps,
            ..s
        }),
        ..rows()
    }
}

/// The rows (visit positions) the head can sweep.
fn sweepable(spec: &ScanSpec) -> Vec<u32> {
    (0..spec.len())
        .filter(|&o| matches!(visit(spec, o), Visit::Row(r) if sweep::row_ends(&REFERENCE, &r).is_ok()))
        .collect()
}

/// The visit positions of the retro points.
fn retro_points(spec: &ScanSpec) -> Vec<u32> {
    (0..spec.len()).filter(|&o| matches!(visit(spec, o), Visit::Point(_))).collect()
}

/// What is visited at position `o`.
fn visit(spec: &ScanSpec, o: u32) -> Visit {
    spec.index_at_order(o)
        .and_then(|i| spec.visit(i, o))
        .unwrap_or_else(|| panic!("no position {o}"))
}

/// The row visited at position `o`.
fn row(spec: &ScanSpec, o: u32) -> SweepRow {
    match visit(spec, o) {
        Visit::Row(r) => r,
        other => panic!("position {o} is not a row: {other:?}"),
    }
}

/// The scan's outcome and its stored samples by visit position: the rows'
/// (swept, with an extent), then the retro points' (at rest).
async fn scan(sim: SimConfig, spec: &ScanSpec) -> (ScanOutcome, BTreeMap<u32, Vec<Row>>, BTreeMap<u32, Vec<Row>>) {
    let mut session = session(Arc::new(Simulated(sim))).await;
    let dir = tempfile::tempdir().unwrap();
    let (outcome, stored) = scan_and_read(&mut session, spec, dir.path()).await;
    session.close().await;
    let (mut by_row, mut retro): (BTreeMap<u32, Vec<Row>>, BTreeMap<u32, Vec<Row>>) = Default::default();
    for r in stored {
        let at = if r.extent_deg.is_some() { &mut by_row } else { &mut retro };
        at.entry(r.order.expect("a scan position")).or_default().push(r);
    }
    (outcome, by_row, retro)
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
        let shadow = REFERENCE.optics.blind_max_deg;
        assert!(near.psi_deg > shadow && near.psi_deg < shadow + 2.0, "row {o} begins at {near:?}");
        assert!((far.theta_o_deg - r.theta_o_stop_deg).abs() < 1.0, "row {o} ends at {far:?}");
        for s in samples {
            assert!((s.theta_i_deg - r.theta_i_deg).abs() < 0.01, "row {o} left its incidence: {s:?}");
            let extent = s.extent_deg.expect("a swept sample's extent");
            assert!(extent > 0.0 && extent < 2.0, "row {o}: extent {extent}° of {s:?}");
        }
    }
}

#[tokio::test]
async fn a_sweep_scan_stores_every_row_it_can_sweep_once_and_whole_and_the_retro_point() {
    let spec = rows();
    let (outcome, by_row, retro) = scan(SimConfig::default(), &spec).await;
    let rows: Vec<u32> = by_row.keys().copied().collect();
    let expected = sweepable(&spec);
    assert!(expected.len() >= 3, "{expected:?}");
    assert_eq!(rows, expected);
    // The incidence's retro point, first, once, at rest through the beam
    // splitter: where no row reaches.
    assert_eq!(retro_points(&spec), vec![0]);
    assert_eq!(retro.keys().copied().collect::<Vec<_>>(), retro_points(&spec));
    let point = &retro[&0];
    assert_eq!(point.len(), 1, "{point:?}");
    let p = &point[0];
    assert!(p.psi_deg.abs() <= REFERENCE.optics.retro_max_deg, "{p:?}");
    assert!((p.theta_o_deg - 30.0).abs() < 0.01 && p.dphi_deg.abs() < 0.1, "{p:?}");
    assert_eq!(outcome.measured as usize, rows.len() + 1);
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
    let (outcome, by_row, _) = scan(sim, &spec).await;
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

#[tokio::test]
async fn a_row_slows_down_across_a_narrow_lobe_so_its_samples_span_a_fraction_of_it() {
    // A lobe 1° wide, a sample at most a quarter of it: 7.2°/s within 3°
    // of the mirror direction (on the Δφ = 180° row at θo = 30°), 20°/s
    // elsewhere (0.70° a sample).
    let spec = slowed(1.0, 20.0);
    let (_, by_row, _) = scan(SimConfig::default(), &spec).await;
    check_whole(&spec, &by_row);
    let (mut slow, mut fast) = (0, 0);
    for samples in by_row.values() {
        let (ends_lo, ends_hi) = samples
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), s| (lo.min(s.psi_deg), hi.max(s.psi_deg)));
        for s in samples {
            let (i, o, d) = (s.theta_i_deg.to_radians(), s.theta_o_deg.to_radians(), s.dphi_deg.to_radians());
            let mirror = (i.cos() * o.cos() - i.sin() * o.sin() * d.cos())
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            let extent = s.extent_deg.unwrap();
            if mirror < 3.0 - 0.5 {
                slow += 1;
                assert!(extent <= 0.25 * 1.01, "{extent}° at {mirror}° from the mirror: {s:?}");
            } else if mirror > 3.0 + 3.5 && s.psi_deg > ends_lo + 4.0 && s.psi_deg < ends_hi - 4.0 {
                // Beyond the ramps back to 20°/s and the row's own ramps.
                fast += 1;
                assert!((extent - 0.696).abs() < 0.02, "{extent}° at {mirror}° from the mirror: {s:?}");
            }
        }
    }
    assert!(slow >= 15 && fast >= 100, "{slow} slow and {fast} fast samples");
}

#[tokio::test]
async fn a_sweep_steps_its_gain_down_across_a_bright_lobe_rather_than_saturate() {
    // A tape whose mirror lobe (n = 1 000) is far brighter than where the
    // Δφ = 180° row begins and its gain is ranged: one or two samples
    // saturate as the row climbs into the lobe, then the gain steps down.
    let mut narrow = Material::tape();
    narrow.params[1] = 1000.0;
    let sim = SimConfig {
        material: Specimen::Model(narrow),
        ..SimConfig::default()
    };
    let spec = rows();
    let (outcome, by_row, _) = scan(sim, &spec).await;
    assert_eq!(by_row.keys().copied().collect::<Vec<_>>(), sweepable(&spec), "{outcome:?}");
    check_whole(&spec, &by_row);
    let mirror = by_row
        .iter()
        .find(|(&o, _)| row(&spec, o).dphi_deg.abs() == 180.0)
        .map(|(_, s)| s)
        .expect("the Δφ = 180° row");
    let gains: std::collections::BTreeSet<u8> = mirror.iter().map(|s| s.gain_index).collect();
    assert!(gains.len() >= 2, "one gain all along: {gains:?}");
    let saturated = |s: &Row| s.flags & SampleFlags::SATURATED.bits() != 0;
    let longest = mirror.split(|s| !saturated(s)).map(<[Row]>::len).max().unwrap_or(0);
    assert!(longest <= 2, "{longest} saturated samples in a row");
}

#[tokio::test]
async fn a_row_whose_slow_stretch_overflows_the_step_queue_runs_slow_all_along() {
    // A lobe 0.05° wide on rows at 30°/s: 0.36°/s across the mirror lobe,
    // 1.2 % of the row's speed; the five ramps from rest, in and out of the
    // slow stretch and to rest take 408 blocks, more than the queue's 384.
    let spec = slowed(0.05, 30.0);
    let crossing = |o: u32| row(&spec, o).dphi_deg.abs() == 180.0;
    for o in sweepable(&spec) {
        let p = sweep::row_plan(&REFERENCE, &row(&spec, o), 230.0).unwrap();
        let blocks = motion::axis_blocks(&REFERENCE, p.delta(), p.limits, &p.levels, 1_000_000);
        assert_eq!(blocks.iter().any(|&n| n > QUEUE), crossing(o), "row {o}: {blocks:?} blocks");
    }
    let (_, by_row, _) = scan(SimConfig::default(), &spec).await;
    assert_eq!(by_row.keys().copied().collect::<Vec<_>>(), sweepable(&spec));
    check_whole(&spec, &by_row);
    for (&o, samples) in &by_row {
        let extents: Vec<f32> = samples.iter().map(|s| s.extent_deg.unwrap()).collect();
        if crossing(o) {
            // 0.0125° a sample at 0.36°/s (within a microstep, 0.0025°)
            // beyond the ramps at the row's ends, short at this speed.
            for e in &extents[extents.len() / 4..extents.len() * 3 / 4] {
                assert!((e - 0.0125).abs() < 0.003, "row {o}: {e}°");
            }
        } else {
            // At 30°/s between its ramps: 1.04° a sample.
            let top = extents.iter().copied().fold(0.0, f32::max);
            assert!((top - 30.0 * 8.0 / 230.0).abs() < 0.03, "row {o}: {top}°");
        }
    }
}
