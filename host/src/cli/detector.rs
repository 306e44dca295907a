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
        if !(self.integration_s.is_finite() && self.integration_s > 0.0 && self.integration_s <= DetectionSettings::INTEGRATION_MAX_S) {
            bail!("--integration-s must be in (0, {}] s", DetectionSettings::INTEGRATION_MAX_S);
        }
        let reference = match self.reference {
            ReferenceArg::Square => Reference::Square,
            ReferenceArg::Sine => Reference::Sine,
            ReferenceArg::Matched => Reference::Matched,
        };
        let calibrate_at = match &self.calibrate_at {
            None if reference == Reference::Matched => bail!("--reference matched needs --calibrate-at TI,TO,DPHI"),
            None => None,
            Some(s) => Some(parse_geometry(s).context("--calibrate-at")?),
        };
        Ok(DetectorPlan {
            reference,
            calibrate_at,
            integration_s: self.integration_s,
        })
    }
}

/// The detector's part of a scan's plan (`scan.json`): checked values, so
/// that a resumed scan measures exactly as its start did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetectorPlan {
    /// Demodulation reference.
    pub reference: Reference,
    /// Where the detector learns its phase and waveform before the scan.
    pub calibrate_at: Option<Geometry>,
    /// Integration time per point (s), rounded to whole chop periods.
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
