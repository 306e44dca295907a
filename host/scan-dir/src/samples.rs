//! `samples.csv` and `reference.csv`: one row per measured sample, raw
//! values as the head reported them. A scan's rows are written and flushed
//! as they arrive, to `samples.csv.part` until the scan completes, so a file
//! called `samples.csv` is always a whole scan. Columns: `docs/samples-csv.md`.

use crate::swept;
use crate::ScanDir;
use anyhow::{Context, Result};
use gonio_shared::{Sample, SampleFlags, Signal, SweptSample};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::path::{Path, PathBuf};

/// One row; field names are the CSV header.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub seq: u32,
    pub index: Option<u32>,
    pub order: Option<u32>,
    pub timestamp_s: f64,
    pub target_theta_i_deg: f32,
    pub target_theta_o_deg: f32,
    pub target_dphi_deg: f32,
    pub theta_i_deg: f32,
    pub theta_o_deg: f32,
    pub dphi_deg: f32,
    pub omega_deg: f32,
    pub tau_deg: f32,
    pub psi_deg: f32,
    pub in_phase_v: f32,
    pub quadrature_v: f32,
    pub amplitude_v: f32,
    pub magnitude_v: f32,
    pub phase_deg: f32,
    pub noise_v: f32,
    pub gain_v_per_a: f32,
    pub gain_index: u8,
    pub periods: u16,
    pub flags: u16,
    pub flag_names: String,
    /// A swept sample's angular extent (degrees, [`swept::extent_deg`]);
    /// empty for a sample at rest (and absent in files of an earlier gonio).
    #[serde(default)]
    pub extent_deg: Option<f32>,
}

impl Row {
    /// The `flags` column as the bit set it stores.
    pub fn sample_flags(&self) -> SampleFlags {
        SampleFlags::from_bits_retain(self.flags)
    }
}

impl From<&Sample> for Row {
    fn from(s: &Sample) -> Self {
        let mut row = Row::of_signal(s.seq, s.scan, s.timestamp_us as f64 * 1e-6, &s.signal);
        (row.target_theta_i_deg, row.target_theta_o_deg, row.target_dphi_deg) =
            (s.target.theta_i_deg, s.target.theta_o_deg, s.target.dphi_deg);
        (row.theta_i_deg, row.theta_o_deg, row.dphi_deg) = (s.reached.theta_i_deg, s.reached.theta_o_deg, s.reached.dphi_deg);
        (row.omega_deg, row.tau_deg, row.psi_deg) = (s.axes.omega_deg, s.axes.tau_deg, s.axes.psi_deg);
        row
    }
}

/// A swept sample's row: it has no target, so its geometry (the middle of
/// its stage angles, [`swept::geometry`]) stands in both; its time is its
/// middle, and its extent is filled in.
impl From<&SweptSample> for Row {
    fn from(s: &SweptSample) -> Self {
        let middle_s = s.start_us as f64 * 1e-6 + 0.5 * s.duration_s as f64;
        let mut row = Row::of_signal(s.seq, s.scan, middle_s, &s.signal);
        let (g, a) = (swept::geometry(s), s.mid_axes());
        (row.target_theta_i_deg, row.target_theta_o_deg, row.target_dphi_deg) = (g.theta_i_deg, g.theta_o_deg, g.dphi_deg);
        (row.theta_i_deg, row.theta_o_deg, row.dphi_deg) = (g.theta_i_deg, g.theta_o_deg, g.dphi_deg);
        (row.omega_deg, row.tau_deg, row.psi_deg) = (a.omega_deg, a.tau_deg, a.psi_deg);
        row.extent_deg = Some(swept::extent_deg(s) as f32);
        row
    }
}

impl Row {
    /// The row of a signal, its geometry and stage angles left at zero.
    fn of_signal(seq: u32, scan: Option<gonio_shared::sample::ScanPosition>, timestamp_s: f64, signal: &Signal) -> Self {
        let names: Vec<String> = signal.flags.iter_names().map(|(n, _)| n.to_ascii_lowercase()).collect();
        Row {
            seq,
            index: scan.map(|p| p.index),
            order: scan.map(|p| p.order),
            timestamp_s,
            target_theta_i_deg: 0.0,
            target_theta_o_deg: 0.0,
            target_dphi_deg: 0.0,
            theta_i_deg: 0.0,
            theta_o_deg: 0.0,
            dphi_deg: 0.0,
            omega_deg: 0.0,
            tau_deg: 0.0,
            psi_deg: 0.0,
            in_phase_v: signal.in_phase_v,
            quadrature_v: signal.quadrature_v,
            amplitude_v: signal.amplitude_v,
            magnitude_v: signal.magnitude_v,
            phase_deg: signal.phase_deg,
            noise_v: signal.noise_v,
            gain_v_per_a: signal.gain_v_per_a,
            gain_index: signal.gain_index,
            periods: signal.periods,
            flags: signal.flags.bits(),
            flag_names: names.join("|"),
            extent_deg: None,
        }
    }
}

/// Writes `reference.csv`: the reference plate's samples, in the columns
/// of `samples.csv`.
pub fn write_reference(dir: &Path, samples: &[Sample]) -> Result<PathBuf> {
    let path = ScanDir::new(dir).reference();
    let mut w = csv::Writer::from_path(&path).with_context(|| format!("creating {}", path.display()))?;
    for s in samples {
        w.serialize(Row::from(s))?;
    }
    w.flush().with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// Appends rows durably while a scan runs.
pub struct SampleWriter {
    csv: csv::Writer<File>,
    part: PathBuf,
    done: PathBuf,
}

impl SampleWriter {
    pub fn create(dir: &Path) -> Result<Self> {
        let part = ScanDir::new(dir).samples_part();
        let file = File::create(&part).with_context(|| format!("creating {}", part.display()))?;
        Ok(SampleWriter {
            csv: csv::Writer::from_writer(file),
            part,
            done: ScanDir::new(dir).samples(),
        })
    }

    /// Appends to the samples of an interrupted scan. A last line cut short
    /// by a crash is dropped (its point is measured again); a file of an
    /// earlier gonio, whose columns end before `extent_deg`, is first
    /// written again in today's (its rows would not read back beside the
    /// new ones otherwise).
    pub fn append(dir: &Path) -> Result<Self> {
        let part = ScanDir::new(dir).samples_part();
        if !part.exists() {
            return Self::create(dir);
        }
        let text = whole_lines(&part)?;
        let header = text.split(|&b| b == b'\n').next().unwrap_or_default();
        if !text.is_empty() && !header.trim_ascii_end().ends_with(b"extent_deg") {
            // Beside the file, then over it: a crash meanwhile loses nothing.
            let rows = stored_rows(dir)?;
            let new = part.with_extension("part.new");
            let mut w = csv::Writer::from_path(&new).with_context(|| format!("creating {}", new.display()))?;
            for r in &rows {
                w.serialize(r).context("writing a sample row")?;
            }
            w.flush()?;
            w.get_ref().sync_all().context("syncing samples")?;
            std::fs::rename(&new, &part).with_context(|| format!("renaming to {}", part.display()))?;
            return Self::append(dir);
        }
        let whole = text.len();
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(&part)
            .with_context(|| format!("opening {}", part.display()))?;
        file.set_len(whole as u64).context("dropping a partial last line")?;
        let mut file = file;
        std::io::Seek::seek(&mut file, std::io::SeekFrom::End(0))?;
        Ok(SampleWriter {
            csv: csv::WriterBuilder::new().has_headers(whole == 0).from_writer(file),
            part,
            done: ScanDir::new(dir).samples(),
        })
    }

    /// Writes one sample and flushes it to the operating system.
    pub fn push(&mut self, s: &Sample) -> Result<()> {
        self.write(&[Row::from(s)])
    }

    /// Writes a sweep scan's row of samples together and flushes them (a
    /// crash can still cut it short: resuming sweeps the last stored row
    /// again, [`drop_last_position`]).
    pub fn push_swept(&mut self, row: &[SweptSample]) -> Result<()> {
        self.write(&row.iter().map(Row::from).collect::<Vec<_>>())
    }

    fn write(&mut self, rows: &[Row]) -> Result<()> {
        for r in rows {
            self.csv.serialize(r).context("writing a sample row")?;
        }
        self.csv.flush().context("flushing samples")
    }

    /// Syncs the file and gives it its final name.
    pub fn finish(mut self) -> Result<PathBuf> {
        self.csv.flush()?;
        self.csv.get_ref().sync_all().context("syncing samples")?;
        std::fs::rename(&self.part, &self.done).with_context(|| format!("renaming to {}", self.done.display()))?;
        Ok(self.done)
    }
}

/// The bytes of a file up to its last newline: the rows written whole
/// (a crash can cut the last one short).
fn whole_lines(path: &Path) -> Result<Vec<u8>> {
    let mut text = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    text.truncate(text.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1));
    Ok(text)
}

/// The rows an interrupted scan stored whole in `dir` (none if it stored nothing).
pub fn stored_rows(dir: &Path) -> Result<Vec<Row>> {
    let part = ScanDir::new(dir).samples_part();
    if !part.exists() {
        return Ok(Vec::new());
    }
    let text = whole_lines(&part)?;
    csv::Reader::from_reader(&text[..])
        .deserialize()
        .enumerate()
        .map(|(i, row)| row.with_context(|| format!("{}: row {}", part.display(), i + 2)))
        .collect()
}

/// Drops the samples of the last visit position an interrupted scan stored
/// (with a partial last line): a sweep scan's row may have been cut short
/// by a crash while it was written, and is swept again.
pub fn drop_last_position(dir: &Path) -> Result<()> {
    let part = ScanDir::new(dir).samples_part();
    if !part.exists() {
        return Ok(());
    }
    let text = whole_lines(&part)?;
    let mut reader = csv::Reader::from_reader(&text[..]);
    let headers = reader.headers().context("reading the stored samples")?.clone();
    let mut keep = text.len() as u64;
    let mut last = None;
    loop {
        let at = reader.position().byte();
        let mut record = csv::StringRecord::new();
        if !reader.read_record(&mut record).context("reading the stored samples")? {
            break;
        }
        let row: Row = record.deserialize(Some(&headers)).context("reading the stored samples")?;
        if row.order.is_some() && row.order != last {
            (keep, last) = (at, row.order);
        }
    }
    if last.is_some() {
        let file = std::fs::OpenOptions::new()
            .write(true)
            .open(&part)
            .with_context(|| format!("opening {}", part.display()))?;
        file.set_len(keep).context("dropping the last stored position")?;
    }
    Ok(())
}

/// Reads a samples file back.
pub fn read(path: &Path) -> Result<Vec<Row>> {
    let mut r = csv::Reader::from_path(path).with_context(|| format!("opening {}", path.display()))?;
    r.deserialize()
        .enumerate()
        .map(|(i, row)| row.with_context(|| format!("{}: row {}", path.display(), i + 2)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_shared::sample::ScanPosition;
    use gonio_shared::{AxisAngles, Signal};

    fn swept(seq: u32, order: u32) -> SweptSample {
        let at = |psi: f32| AxisAngles {
            omega_deg: 20.0,
            tau_deg: 5.0,
            psi_deg: psi,
        };
        SweptSample {
            seq,
            scan: Some(ScanPosition { index: order, order }),
            start_us: seq as u64 * 35_000,
            duration_s: 0.035,
            axes_from: at(10.0 + seq as f32),
            axes_to: at(11.0 + seq as f32),
            signal: Signal {
                in_phase_v: 0.1,
                quadrature_v: 0.0,
                amplitude_v: 0.1,
                magnitude_v: 0.1,
                phase_deg: 0.0,
                noise_v: 1e-4,
                gain_v_per_a: 1e6,
                gain_index: 1,
                periods: 8,
                flags: SampleFlags::empty(),
            },
        }
    }

    /// A scan an earlier gonio began (no `extent_deg` column) resumes into
    /// a file that reads back whole.
    #[test]
    fn a_file_of_an_earlier_gonio_is_appended_to_in_todays_columns() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = SampleWriter::create(dir.path()).unwrap();
        w.push_swept(&[swept(0, 0), swept(1, 1)]).unwrap();
        drop(w);
        let part = ScanDir::new(dir.path()).samples_part();
        let text = String::from_utf8(std::fs::read(&part).unwrap()).unwrap();
        let old: String = text.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n").collect();
        std::fs::write(&part, old).unwrap();
        let mut w = SampleWriter::append(dir.path()).unwrap();
        w.push_swept(&[swept(2, 2)]).unwrap();
        drop(w);
        let rows = stored_rows(dir.path()).unwrap();
        assert_eq!(rows.iter().map(|r| r.seq).collect::<Vec<_>>(), [0, 1, 2]);
        assert_eq!(
            rows.iter().map(|r| r.extent_deg.is_some()).collect::<Vec<_>>(),
            [false, false, true]
        );
    }

    /// An interrupted sweep scan resumes at its last stored row, whose
    /// samples (and a line a crash cut short) are dropped: the row is swept
    /// again whole; the header stays, or is written again for a first row.
    #[test]
    fn resuming_a_sweep_scan_drops_its_last_stored_row() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = SampleWriter::create(dir.path()).unwrap();
        w.push_swept(&[swept(0, 0), swept(1, 0)]).unwrap();
        w.push_swept(&[swept(2, 1), swept(3, 1), swept(4, 1)]).unwrap();
        drop(w);
        let part = ScanDir::new(dir.path()).samples_part();
        let mut text = std::fs::read(&part).unwrap();
        text.extend_from_slice(b"5,2,2,0.1");
        std::fs::write(&part, text).unwrap();

        drop_last_position(dir.path()).unwrap();
        let kept = stored_rows(dir.path()).unwrap();
        assert_eq!(
            kept.iter().map(|r| (r.seq, r.order)).collect::<Vec<_>>(),
            [(0, Some(0)), (1, Some(0))]
        );
        assert!(kept.iter().all(|r| r.extent_deg.is_some_and(|e| (e - 1.0).abs() < 0.01)));

        let mut w = SampleWriter::append(dir.path()).unwrap();
        w.push_swept(&[swept(5, 1), swept(6, 1)]).unwrap();
        drop(w);
        assert_eq!(stored_rows(dir.path()).unwrap().len(), 4);

        // Dropped row by row down to nothing: appending starts over.
        drop_last_position(dir.path()).unwrap();
        drop_last_position(dir.path()).unwrap();
        assert!(stored_rows(dir.path()).unwrap().is_empty());
        let mut w = SampleWriter::append(dir.path()).unwrap();
        w.push_swept(&[swept(7, 0)]).unwrap();
        drop(w);
        assert_eq!(stored_rows(dir.path()).unwrap().len(), 1);
    }
}
