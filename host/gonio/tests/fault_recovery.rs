//! The host's half of the fault matrix (docs/faults.md): every
//! fault injected into the simulated head (`gonio scan --sim --inject`), run
//! as a user runs it. Link faults and transient hardware faults are
//! recovered during the scan; lasting hardware faults end it with the fault
//! named and the way to resume, and the resumed scan (on the repaired head)
//! completes. Either way the stored samples are exactly the grid: no
//! position twice, none missing. The head's half (safe state when each
//! fault is reported) is tests/tests/fault_safe_state.rs.

use std::collections::BTreeSet;
use std::path::Path;

mod common;
use common::{gonio, text};

const GRID: [&str; 7] = [
    "--theta-i",
    "30",
    "--theta-o",
    "0:60:6",
    "--dphi=-180:180:30",
    "--no-patterns",
    "--json",
];
const POINTS: usize = 11 * 13;

/// The grid's points the head reaches (θo = 24° and 36° at Δφ = 0 lie in
/// the plate's shadow, 6° from the laser).
fn reachable() -> BTreeSet<u32> {
    common::reachable(&gonio_shared::ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[30.0]).unwrap(),
        theta_o: gonio_shared::AngleRange::new(0.0, 60.0, 6.0),
        dphi: gonio_shared::AngleRange::new(-180.0, 180.0, 30.0),
        first_order: 0,
        sweep: None,
        patterns: None,
    })
}

/// The scan positions stored in the completed scan, each checked unique.
fn stored_indices(dir: &Path) -> BTreeSet<u32> {
    let text = std::fs::read_to_string(dir.join("samples.csv")).expect("a completed scan");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "index").unwrap();
    let idx: Vec<u32> = lines.filter_map(|l| l.split(',').nth(col).unwrap().parse().ok()).collect();
    let set: BTreeSet<u32> = idx.iter().copied().collect();
    assert_eq!(set.len(), idx.len(), "a position stored twice");
    set
}

fn scan(dir: &Path, inject: &str) -> std::process::Output {
    let mut args = vec!["scan", "--sim", "--out", dir.to_str().unwrap(), "--inject", inject];
    args.extend(GRID);
    gonio(&args)
}

/// What the scan summary says was recovered.
#[derive(Debug, Clone, Copy)]
enum Recovery {
    /// Nothing needed recovering.
    None,
    /// A recovery whose name contains this.
    Named(&'static str),
    /// A race decides: a late request may be answered before the host's
    /// probe (nothing to recover) or after it (taken as lost, reconnected).
    NoneOr(&'static str),
}
use Recovery::{Named, NoneOr};

/// Faults recovered during the scan (or while preparing the head for it):
/// how the summary names the recovery.
#[test]
fn link_and_transient_faults_are_recovered_without_losing_or_repeating_a_sample() {
    let all = reachable();
    assert_eq!(all.len(), POINTS - 2);
    for (inject, recovered) in [
        ("drop@60", Named("events lost or out of order")),
        ("corrupt@60", Named("events lost or out of order")),
        ("reorder@60", Named("events lost or out of order")),
        ("duplicate@60", Recovery::None),
        ("delay@60:300", Recovery::None),
        // Frames 1–7 answer the setup, 8 the scan request; then the five
        // chunks of the visit order are answered among the first points' events,
        // so 9–156 are the 143 points' events and 5 chunk replies (156 the
        // last sample), 157 the end of the scan, whose loss the host
        // notices by asking the head (no recovery needed).
        ("drop@156", Named("events lost or out of order")),
        ("drop@157", Recovery::None),
        ("disconnect@60", Named("link lost")),
        ("stall@30", Named("E402")),
        ("overrun@30:1", Recovery::None),
        ("overrun@30:40", Named("E500")),
        ("drop@40,duplicate@50,reorder@70,corrupt@90,disconnect@120", Named("link lost")),
        // The host's requests: 1 identify, 2 mechanics, 3 abort (whatever
        // the head was doing), 4 detection settings, 5 homing, 6 detection
        // settings, 7 safety settings, 8 the scan. A lost request (or
        // answer) is found by the probe that follows an unanswered request,
        // at once instead of after the request's timeout.
        ("drop@8", Named("was lost")),
        ("req-drop@8", Named("was lost")),
        ("req-corrupt@8", Named("was lost")),
        ("req-reorder@8", NoneOr("was lost")),
        ("req-duplicate@8", Recovery::None),
        // 9–13 are the visit chunks, 10 sent while the first points are
        // measured: the head keeps no request then, so it is lost too.
        ("req-drop@10", Named("was lost")),
        ("req-delay@8:300", Recovery::None),
        ("req-disconnect@8", Named("link lost")),
        // Lost while preparing the head (homing): found again before the scan starts.
        ("req-drop@5", Named("while preparing the head")),
        ("req-duplicate@5", Recovery::None),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let o = scan(dir.path(), inject);
        assert!(o.status.success(), "{inject}: {}", text(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["measured"].as_u64(), Some(all.len() as u64), "{inject}: {v}");
        assert_eq!(stored_indices(dir.path()), all, "{inject}: stored positions");
        let recoveries = v["recoveries"].as_object().unwrap();
        let named = |r: &str| recoveries.keys().any(|k| k.contains(r));
        let as_expected = match recovered {
            Recovery::None => recoveries.is_empty(),
            Named(r) => named(r),
            NoneOr(r) => recoveries.is_empty() || named(r),
        };
        assert!(as_expected, "{inject}: expected {recovered:?}: {v}");
        if inject.starts_with("duplicate") {
            assert_eq!(v["duplicates_dropped"].as_u64(), Some(1), "{inject}: {v}");
        }
    }
}

/// Lasting faults: the scan ends with the fault named (non-zero exit), the
/// samples so far are kept, and `--resume` on the repaired head completes it.
#[test]
fn lasting_faults_end_the_scan_named_and_resumable() {
    let all = reachable();
    for (inject, code) in [
        ("saturated@30", "E501"),
        ("laser-dead@30", "E504"),
        ("switch-open@0:1", "E400"),
        ("switch-closed@0:0", "E401"),
        ("stall@30,stall@30,stall@30,stall@30,stall@30,stall@30,stall@30", "E402"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let o = scan(dir.path(), inject);
        assert!(!o.status.success(), "{inject}: {}", text(&o));
        let err = text(&o);
        assert!(err.contains(code), "{inject}: {err}");
        assert!(!err.contains("panicked"), "{inject}: {err}");
        if !inject.starts_with("switch") {
            assert!(err.contains("gonio scan --resume"), "{inject}: {err}");
        }
        let o = gonio(&["scan", "--resume", dir.path().to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{inject}, resumed: {}", text(&o));
        assert_eq!(stored_indices(dir.path()), all, "{inject}: stored positions after resuming");
    }
}

/// Ctrl-C in the middle of a scan: the head is stopped through the client,
/// the operator is told where the scan stands and how to resume, the exit
/// code is 130, and the resumed scan completes the grid exactly.
#[test]
fn ctrl_c_stops_the_scan_says_how_to_resume_and_the_resume_completes_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scan");
    // One incidence with its rings: long enough to be interrupted.
    let grid = ["--theta-i", "30", "--dphi=-180:180:10"];
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_gonio"))
        .args([&["scan", "--sim", "--out", out.to_str().unwrap()][..], &grid].concat())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let part = out.join("samples.csv.part");
    let rows = || std::fs::read_to_string(&part).map_or(0, |t| t.lines().count());
    let t0 = std::time::Instant::now();
    while rows() < 50 {
        assert!(t0.elapsed().as_secs() < 120, "the scan never started");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let msg = text(&o);
    assert_eq!(o.status.code(), Some(130), "{msg}");
    assert!(
        msg.contains("interrupted at position") && msg.contains("the head is safe (laser off, drivers off)"),
        "{msg}"
    );
    assert!(msg.contains(&format!("gonio scan --resume {}", out.display())), "{msg}");
    assert!(!out.join("samples.csv").exists(), "an interrupted scan is not complete");
    let o = gonio(&["scan", "--resume", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    // The whole scan's counts: the skipped ones' reasons add up to them.
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let reasons: u64 = summary["skipped_by_reason"]
        .as_object()
        .unwrap()
        .values()
        .map(|n| n.as_u64().unwrap())
        .sum();
    assert_eq!(summary["skipped"].as_u64(), Some(reasons), "{summary}");
    let spec = gonio_shared::ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[30.0]).unwrap(),
        dphi: gonio_shared::AngleRange::new(-180.0, 180.0, 10.0),
        ..gonio_shared::ScanSpec::belcour_with_patterns()
    };
    assert_eq!(stored_indices(&out), common::reachable(&spec));
}
