//! What measured a data file, as the user states it: the apertures its
//! values are the average over, and the wavelength. A file this head did
//! not write is of an instrument not known until its header or these say.

use anyhow::Result;
use gonio_analysis::instrument::Instrument;

#[derive(Debug, Clone, Default, clap::Args)]
pub struct InstrumentArgs {
    /// The instrument's source aperture (angular diameter seen from the
    /// sample, degrees), for a file another instrument measured; with
    /// --instrument-receiver-deg. Replaces what the file's header states.
    #[arg(long, value_name = "DEG", requires = "instrument_receiver_deg")]
    pub instrument_source_deg: Option<f64>,
    /// ...its receiver (detector) aperture, degrees.
    #[arg(long, value_name = "DEG", requires = "instrument_source_deg")]
    pub instrument_receiver_deg: Option<f64>,
    /// ...its wavelength (nm), with the apertures.
    #[arg(long, value_name = "NM", requires = "instrument_source_deg")]
    pub instrument_wavelength_nm: Option<f64>,
}

impl InstrumentArgs {
    /// The instrument stated here, if any.
    pub fn stated(&self) -> Result<Option<Instrument>> {
        if self.instrument_source_deg.is_none() {
            return Ok(None);
        }
        Instrument::stated(
            self.instrument_source_deg,
            self.instrument_receiver_deg,
            self.instrument_wavelength_nm,
        )
        .map(Some)
    }
}
