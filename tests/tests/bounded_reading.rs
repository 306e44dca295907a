//! Reading a data file needs bounded memory whatever the file's size: a
//! valid CSV of five million rows (60 MB) is refused at the row limit, and
//! this process's peak resident memory (its own test binary, so no other
//! test shares it) stays under 200 MB, where holding the file and its rows
//! would take more than 500 MB.

use gonio_analysis::formats::{self, guard::MAX_ROWS};
use std::io::Write;

/// This process's peak resident set size in bytes (Linux's `VmHWM`).
fn peak_rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[test]
fn a_file_past_the_row_limit_is_refused_in_bounded_memory() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("large.csv");
    let mut out = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    out.write_all(b"theta_i_deg,theta_o_deg,dphi_deg,brdf_sr\n").unwrap();
    for k in 0..5 * MAX_ROWS {
        writeln!(out, "{},20.5,0,1", k % 80).unwrap();
    }
    out.flush().unwrap();
    drop(out);
    assert!(std::fs::metadata(&path).unwrap().len() > 50_000_000);
    let e = formats::load(&path, None).unwrap_err();
    assert!(format!("{e:#}").contains(&format!("more than {MAX_ROWS} samples")), "{e:#}");
    match peak_rss() {
        Some(peak) => assert!(peak < 200 * 1024 * 1024, "peak resident memory {peak} B"),
        None => eprintln!("no /proc/self/status here: the peak was not measured"),
    }
}
