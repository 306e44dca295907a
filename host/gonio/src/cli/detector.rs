//! Detector options of a scan (the reference waveform, where the detector
//! learns it, the integration time) as the command line gives them.

use anyhow::{Context, Result};
use gonio_scan_dir::record::{parse_geometry, DetectorChoice};
use gonio_shared::Reference;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ReferenceArg {
    Square,
    Sine,
    /// The signal's own waveform, learned by --learn-at: reaches the noise limit.
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
    pub learn_at: Option<String>,
    /// Integration time per point (s), rounded to whole chop periods.
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub integration_s: f32,
}

impl DetectorArgs {
    /// The demo's: matched reference learned on the tape's retro peak at 30°.
    pub fn demo() -> Self {
        DetectorArgs {
            reference: ReferenceArg::Matched,
            learn_at: Some("30,30,0".into()),
            integration_s: 0.1,
        }
    }

    /// The options checked, as the scan's record keeps them.
    pub fn checked(&self) -> Result<DetectorChoice> {
        DetectorChoice {
            reference: match self.reference {
                ReferenceArg::Square => Reference::Square,
                ReferenceArg::Sine => Reference::Sine,
                ReferenceArg::Matched => Reference::Matched,
            },
            learn_at: self.learn_at.as_deref().map(parse_geometry).transpose().context("--learn-at")?,
            integration_s: self.integration_s,
        }
        .check()
    }
}
