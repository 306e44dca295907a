//! Detector options of a scan (the reference waveform, its calibration and
//! the integration time) as the command line gives them, and as the scan's
//! plan keeps them once checked.

use anyhow::{bail, Context, Result};
use gonio_shared::{DetectionSettings, Geometry, Reference};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ReferenceArg {
    Square,
    Sine,
    /// The signal's own waveform, learned by --calibrate-at: reaches the noise limit.
    Matched,
}

#[derive(Debug, Clone, clap::Args)]
pub struct DetectorArgs {
    /// Demodulation reference.
    #[arg(long, value_enum, default_value = "square")]
    pub reference: ReferenceArg,
    /// Before scanning, learn the detector's phase and waveform at this
    /// geometry, THETA_I,THETA_O,DPHI in degrees: put a strong, steady
    /// target there (the reference plate, or the retro peak of the sample).
    #[arg(long, value_name = "TI,TO,DPHI", allow_hyphen_values = true)]
    pub calibrate_at: Option<String>,
    /// Integration time per point (s), rounded to whole chop periods.
    #[arg(long, default_value_t = 0.1)]
    pub integration_s: f32,
}

impl DetectorArgs {
    /// The demo's: matched reference learned on the tape's retro peak at 30°.
    pub fn demo() -> Self {
        DetectorArgs {
            reference: ReferenceArg::Matched,
            calibrate_at: Some("30,30,0".into()),
            integration_s: 0.1,
        }
    }

    /// The options checked, as the plan keeps them.
    pub fn checked(&self) -> Result<DetectorPlan> {
        DetectorPlan {
            reference: match self.reference {
                ReferenceArg::Square => Reference::Square,
                ReferenceArg::Sine => Reference::Sine,
                ReferenceArg::Matched => Reference::Matched,
            },
            calibrate_at: self
                .calibrate_at
                .as_deref()
                .map(parse_geometry)
                .transpose()
                .context("--calibrate-at")?,
            integration_s: self.integration_s,
        }
        .check()
    }
}

/// The detector's part of a scan's plan (`scan.json`): checked values, so
/// that a resumed scan measures exactly as its start did. Read back, it is
/// checked again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "StoredDetector")]
pub struct DetectorPlan {
    /// Demodulation reference.
    pub reference: Reference,
    /// Where the detector learns its phase and waveform before the scan.
    pub calibrate_at: Option<Geometry>,
    /// Integration time per point as asked (s); the head integrates whole
    /// chop periods ([`DetectorPlan::settings`]).
    pub integration_s: f32,
}

impl DetectorPlan {
    /// The head's detection settings for this plan.
    pub fn settings(&self) -> DetectionSettings {
        let base = DetectionSettings::default();
        DetectionSettings {
            periods: base.periods_for(self.integration_s),
            reference: self.reference,
            ..base
        }
    }

    fn check(self) -> Result<Self> {
        if !(self.integration_s.is_finite() && self.integration_s > 0.0 && self.integration_s <= DetectionSettings::INTEGRATION_MAX_S) {
            bail!("--integration-s must be in (0, {}] s", DetectionSettings::INTEGRATION_MAX_S);
        }
        if self.reference == Reference::Matched && self.calibrate_at.is_none() {
            bail!("--reference matched needs --calibrate-at TI,TO,DPHI");
        }
        Ok(self)
    }
}

/// The detector in `scan.json` as read: this plan, or the command line's
/// options as gonio wrote them before it had a plan of its own (so that a
/// scan interrupted under an older gonio resumes).
#[derive(Deserialize)]
#[serde(untagged)]
enum StoredDetector {
    Plan {
        reference: Reference,
        calibrate_at: Option<Geometry>,
        integration_s: f32,
    },
    Options {
        reference: String,
        calibrate_at: Option<String>,
        integration_s: f32,
    },
}

impl TryFrom<StoredDetector> for DetectorPlan {
    type Error = anyhow::Error;

    fn try_from(stored: StoredDetector) -> Result<Self> {
        match stored {
            StoredDetector::Plan {
                reference,
                calibrate_at,
                integration_s,
            } => DetectorPlan {
                reference,
                calibrate_at,
                integration_s,
            }
            .check(),
            StoredDetector::Options {
                reference,
                calibrate_at,
                integration_s,
            } => DetectorArgs {
                reference: clap::ValueEnum::from_str(&reference, true).map_err(|e| anyhow::anyhow!("reference: {e}"))?,
                calibrate_at,
                integration_s,
            }
            .checked(),
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

    /// `scan.json` as gonio wrote it before the plan had a type of its own
    /// (the command line's options) resumes as the same plan.
    #[test]
    fn a_plan_written_as_options_reads_as_the_same_plan() {
        let old = r#"{"reference":"matched","calibrate_at":"30,30,0","integration_s":0.1}"#;
        let plan: DetectorPlan = serde_json::from_str(old).unwrap();
        assert_eq!(plan, DetectorArgs::demo().checked().unwrap());
        let again: DetectorPlan = serde_json::from_str(&serde_json::to_string(&plan).unwrap()).unwrap();
        assert_eq!(again, plan);
    }

    #[test]
    fn a_plan_read_back_is_checked_again() {
        for bad in [
            r#"{"reference":"Square","calibrate_at":null,"integration_s":0.0}"#,
            r#"{"reference":"Matched","calibrate_at":null,"integration_s":0.1}"#,
            r#"{"reference":"square","calibrate_at":"30,x,0","integration_s":0.1}"#,
            r#"{"reference":"cosine","calibrate_at":null,"integration_s":0.1}"#,
        ] {
            assert!(serde_json::from_str::<DetectorPlan>(bad).is_err(), "{bad}");
        }
    }
}
