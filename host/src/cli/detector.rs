//! Detector options of a scan: the reference waveform, its calibration and
//! the integration time.

use anyhow::{bail, Context, Result};
use gonio_shared::{DetectionSettings, Geometry, Reference};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReferenceArg {
    Square,
    Sine,
    /// The signal's own waveform, learned by --calibrate-at: reaches the noise limit.
    Matched,
}

#[derive(Debug, Clone, clap::Args, serde::Serialize, serde::Deserialize)]
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

    /// Settings for the scan and the calibration geometry, checked.
    pub fn plan(&self) -> Result<(DetectionSettings, Option<Geometry>)> {
        let base = DetectionSettings::default();
        if !(self.integration_s.is_finite() && self.integration_s > 0.0 && self.integration_s <= DetectionSettings::INTEGRATION_MAX_S) {
            bail!("--integration-s must be in (0, {}] s", DetectionSettings::INTEGRATION_MAX_S);
        }
        let settings = DetectionSettings {
            periods: base.periods_for(self.integration_s),
            reference: match self.reference {
                ReferenceArg::Square => Reference::Square,
                ReferenceArg::Sine => Reference::Sine,
                ReferenceArg::Matched => Reference::Matched,
            },
            ..base
        };
        let at = match &self.calibrate_at {
            None if settings.reference == Reference::Matched => bail!("--reference matched needs --calibrate-at TI,TO,DPHI"),
            None => None,
            Some(s) => Some(parse_geometry(s).context("--calibrate-at")?),
        };
        Ok((settings, at))
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
