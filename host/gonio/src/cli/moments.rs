//! `gonio moments FILE`: the retro lobe's central moments per incidence in
//! the back and light-view planes (Belcour et al. 2014 §3.D, Fig. 6).

use anyhow::Result;
use gonio_analysis::fit::Units;
use gonio_analysis::moments::{self, Threshold};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct MomentsArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// What is not the retro lobe: below `rel:Q`, a fraction Q of f_r in the
    /// retro direction, or below V sr⁻¹. It keeps the diffuse term and the
    /// mirror lobe out; the default keeps a lobe up to 3° wide within the
    /// reference head's retro rings.
    #[arg(long, default_value = "rel:0.3", value_parser = clap::value_parser!(Threshold))]
    pub threshold: Threshold,
    /// What the file's values are, where it does not say (ALTA without #PARAM_OUT).
    #[arg(long, value_enum)]
    pub units: Option<Units>,
    /// Draw r against θi in both planes into this directory (PNG and SVG), as the paper's Fig. 6.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Print one JSON object: every incidence in both planes (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub instrument: super::instrument::InstrumentArgs,
}

pub fn moments_cmd(a: MomentsArgs) -> Result<()> {
    let data = super::load_data(&a.file, a.units, &a.instrument)?;
    let entries = moments::analyse(&data, a.threshold)?;
    let pictures = match &a.plot {
        Some(dir) => gonio_analysis::plot::moments::render(&entries, dir)?,
        None => Vec::new(),
    };
    if a.json {
        let v = serde_json::json!({
            "file": a.file,
            "instrument": data.instrument.to_json(),
            "threshold": a.threshold,
            "order": moments::ORDER,
            "incidences": entries,
            "pictures": pictures,
        });
        println!("{v}");
        return Ok(());
    }
    print!("{}", moments::text::table(&entries, a.threshold, data.instrument.is_this_head()));
    Ok(())
}
