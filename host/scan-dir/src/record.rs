//! `scan.json`: what a scan was asked to do, written before its first sample
//! so `gonio scan --resume DIR` can finish an interrupted scan exactly.

use crate::ScanDir;
use anyhow::{bail, Context, Result};
use gonio_brdf::Specimen;
use gonio_shared::scan::SWEEP_LAYOUT_SINCE;
use gonio_shared::{DetectionSettings, Geometry, Reference, ScanSpec, PROTOCOL_VERSION};
use gonio_sim::{Imperfections, SimConfig};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The sample a scan assumes unless told (mm): a 100 mm square holds the
/// 1 mm beam's footprint at EN 1436's 88.76° (46 mm long at 1/e²) with
/// all but 0.1 % of its light.
pub const SAMPLE_MM: f64 = 100.0;

/// Which head the scan runs on.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RecordedHead {
    Sim(SimHead),
    Port { path: String },
}

/// The simulated head, described well enough to build it again.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SimHead {
    pub material: Specimen,
    pub seed: u64,
    #[serde(default)]
    pub laser_drift: f64,
    #[serde(default)]
    pub clock_start_s: f64,
    #[serde(default)]
    pub imperfections: Imperfections,
    /// Side of the simulated square sample (mm; absent: larger than any
    /// footprint, as in a record of an earlier gonio).
    #[serde(default)]
    pub sample_mm: Option<f64>,
}

impl SimHead {
    /// The head described, without faults (they act on one run: a resume
    /// runs on the repaired head).
    pub fn config(&self) -> SimConfig {
        let mut c = SimConfig {
            material: self.material.clone(),
            seed: self.seed,
            clock_start_s: self.clock_start_s,
            imperfections: Box::new(self.imperfections.clone()),
            sample_mm: self.sample_mm,
            ..SimConfig::default()
        };
        c.photodiode.laser_drift = self.laser_drift;
        c
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScanRecord {
    /// `target` in the records of an earlier gonio.
    #[serde(alias = "target")]
    pub head: RecordedHead,
    pub spec: ScanSpec,
    pub detector: DetectorChoice,
    /// Laser-drift monitor: a geometry measured before, every so many points
    /// during, and after the scan.
    #[serde(default)]
    pub monitor: Option<Monitor>,
    /// Measure the reference plate before the scan (`reference.csv`).
    #[serde(default)]
    pub reference_plate: bool,
    /// The protocol the scan was recorded under (0: by a gonio that did
    /// not keep it): a sweep scan's positions depend on it.
    #[serde(default)]
    pub protocol: u16,
    /// Side of the square sample the operator declared (mm): an incidence
    /// whose beam footprint overfills it is refused before anything moves
    /// (`gonio_firmware::footprint`). Absent in a record of an earlier gonio.
    #[serde(default)]
    pub sample_size_mm: Option<f64>,
}

/// A laser-drift monitor: one geometry of the mounted target, measured
/// before the scan, after every `every` scan positions, and after the scan.
/// Its readings track the laser's power through the scan (`gonio calibrate`
/// interpolates them). The scan is held for it between two points with
/// `gonio/pause` and carried on with `gonio/continue`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Monitor {
    pub at: Geometry,
    pub every: u32,
}

impl ScanRecord {
    /// A scan of the head at port `path`.
    pub fn at_port(path: &str, spec: &ScanSpec, detector: &DetectorChoice) -> Self {
        Self::new(RecordedHead::Port { path: path.to_string() }, spec, detector)
    }

    /// A scan of the simulated head `c` (its faults are not recorded: they
    /// act on this run only).
    pub fn simulated(c: &SimConfig, spec: &ScanSpec, detector: &DetectorChoice) -> Self {
        let head = RecordedHead::Sim(SimHead {
            material: c.material.clone(),
            seed: c.seed,
            laser_drift: c.photodiode.laser_drift,
            clock_start_s: c.clock_start_s,
            imperfections: (*c.imperfections).clone(),
            sample_mm: c.sample_mm,
        });
        Self::new(head, spec, detector)
    }

    fn new(head: RecordedHead, spec: &ScanSpec, detector: &DetectorChoice) -> Self {
        ScanRecord {
            head,
            spec: spec.clone(),
            detector: detector.clone(),
            monitor: None,
            reference_plate: false,
            protocol: PROTOCOL_VERSION,
            sample_size_mm: None,
        }
    }

    /// The material on a simulated head (what the run record keeps as the truth).
    pub fn material(&self) -> Option<Specimen> {
        match &self.head {
            RecordedHead::Sim(h) => Some(h.material.clone()),
            RecordedHead::Port { .. } => None,
        }
    }

    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = ScanDir::new(dir).record();
        std::fs::write(&path, serde_json::to_string_pretty(self)? + "\n").with_context(|| format!("writing {}", path.display()))
    }

    /// The record of the scan in `dir`, to resume: refused for a sweep scan
    /// recorded before its positions took their place
    /// ([`SWEEP_LAYOUT_SINCE`]: the rows turned evenly about the laser, each
    /// incidence's retro point first) or by a later gonio, so that no scan
    /// mixes two layouts.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = ScanDir::new(dir).record();
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("{} holds no scan to resume ({} missing)", dir.display(), path.display()))?;
        let record: Self = serde_json::from_str(&text).with_context(|| format!("reading {}", path.display()))?;
        if record.spec.sweep.is_some() && !(SWEEP_LAYOUT_SINCE..=PROTOCOL_VERSION).contains(&record.protocol) {
            let by = match record.protocol {
                0 => "by an earlier gonio".to_string(),
                p => format!("under protocol {p}"),
            };
            bail!(
                "{} holds a sweep scan recorded {by} (this gonio speaks protocol {PROTOCOL_VERSION}), whose positions may lie elsewhere; scan it again into a new directory",
                dir.display()
            );
        }
        Ok(record)
    }
}

/// The detector as the scan was asked to measure (`scan.json`): checked
/// values, so that a resumed scan measures exactly as its start did. Read
/// back, it is checked again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "StoredDetector")]
pub struct DetectorChoice {
    /// Demodulation reference.
    pub reference: Reference,
    /// Where the detector learns its phase and waveform before the scan.
    pub learn_at: Option<Geometry>,
    /// Integration time per point as asked (s); the head integrates whole
    /// chop periods ([`DetectorChoice::settings`]).
    pub integration_s: f32,
}

impl DetectorChoice {
    /// The head's detection settings for this choice.
    pub fn settings(&self) -> DetectionSettings {
        let base = DetectionSettings::default();
        DetectionSettings {
            periods: base.periods_for(self.integration_s),
            reference: self.reference,
            ..base
        }
    }

    /// Refuses what the head cannot do, in the command line's words.
    pub fn check(self) -> Result<Self> {
        if !(self.integration_s.is_finite() && self.integration_s > 0.0 && self.integration_s <= DetectionSettings::INTEGRATION_MAX_S) {
            bail!(
                "--integration-s {} s: a point's integration time must be longer than 0 s and at most {} s",
                self.integration_s,
                DetectionSettings::INTEGRATION_MAX_S
            );
        }
        if self.reference == Reference::Matched && self.learn_at.is_none() {
            bail!("--reference matched needs --learn-at TI,TO,DPHI");
        }
        Ok(self)
    }
}

/// The detector in `scan.json` as read: this choice, or the command line's
/// options as an earlier gonio wrote them (so that a scan interrupted under
/// it resumes).
#[derive(Deserialize)]
#[serde(untagged)]
enum StoredDetector {
    Choice {
        reference: Reference,
        #[serde(alias = "calibrate_at")]
        learn_at: Option<Geometry>,
        integration_s: f32,
    },
    Options {
        reference: String,
        #[serde(alias = "calibrate_at")]
        learn_at: Option<String>,
        integration_s: f32,
    },
}

impl TryFrom<StoredDetector> for DetectorChoice {
    type Error = anyhow::Error;

    fn try_from(stored: StoredDetector) -> Result<Self> {
        match stored {
            StoredDetector::Choice {
                reference,
                learn_at,
                integration_s,
            } => DetectorChoice {
                reference,
                learn_at,
                integration_s,
            }
            .check(),
            StoredDetector::Options {
                reference,
                learn_at,
                integration_s,
            } => DetectorChoice {
                reference: match reference.to_ascii_lowercase().as_str() {
                    "square" => Reference::Square,
                    "sine" => Reference::Sine,
                    "matched" => Reference::Matched,
                    other => bail!("reference: `{other}` is none of square, sine, matched"),
                },
                learn_at: learn_at.as_deref().map(parse_geometry).transpose().context("--learn-at")?,
                integration_s,
            }
            .check(),
        }
    }
}

/// `THETA_I,THETA_O,DPHI` in degrees (the head refuses what it cannot reach).
pub fn parse_geometry(s: &str) -> Result<Geometry> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>().with_context(|| format!("`{x}` is not a number")))
        .collect::<Result<_>>()?;
    let [ti, to, dp] = v[..] else {
        bail!("takes THETA_I,THETA_O,DPHI (degrees), got `{s}`");
    };
    if v.iter().any(|x| !x.is_finite()) {
        bail!("angles must be finite, got `{s}`");
    }
    Ok(Geometry::new(ti, to, dp))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `scan.json` as an earlier gonio wrote it (the command line's
    /// options) resumes as the same choice.
    #[test]
    fn a_choice_written_as_options_reads_as_the_same_choice() {
        let old = r#"{"reference":"matched","calibrate_at":"30,30,0","integration_s":0.1}"#;
        let choice: DetectorChoice = serde_json::from_str(old).unwrap();
        let demo = DetectorChoice {
            reference: Reference::Matched,
            learn_at: Some(Geometry::new(30.0, 30.0, 0.0)),
            integration_s: 0.1,
        };
        assert_eq!(choice, demo);
        let again: DetectorChoice = serde_json::from_str(&serde_json::to_string(&choice).unwrap()).unwrap();
        assert_eq!(again, choice);
    }

    #[test]
    fn a_choice_read_back_is_checked_again() {
        for bad in [
            r#"{"reference":"Square","learn_at":null,"integration_s":0.0}"#,
            r#"{"reference":"Matched","learn_at":null,"integration_s":0.1}"#,
            r#"{"reference":"square","calibrate_at":"30,x,0","integration_s":0.1}"#,
            r#"{"reference":"cosine","learn_at":null,"integration_s":0.1}"#,
        ] {
            assert!(serde_json::from_str::<DetectorChoice>(bad).is_err(), "{bad}");
        }
    }
}
