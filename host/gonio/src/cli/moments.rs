//! `gonio moments FILE`: the retro lobe's central moments per incidence in
//! the back and light-view planes (Belcour et al. 2014 §3.D, Fig. 6).

use anyhow::Result;
use gonio_analysis::fit::Units;
use gonio_analysis::moments::{self, Entry, Threshold};
use gonio_analysis::rounding::{figure, significant};
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
    print!("{}", table(&entries, a.threshold, data.instrument.is_this_head()));
    Ok(())
}

/// The table of moments; `this_head`: the data are this head's, whose
/// blind zone explains a gap about the retro lobe (another instrument's
/// gaps are its own).
fn table(entries: &[Entry], threshold: Threshold, this_head: bool) -> String {
    let kept = match threshold {
        Threshold::Relative(q) => format!("f_r at or above {} % of its retro value", significant(100.0 * q, 3)),
        Threshold::Absolute(v) => format!("f_r at or above {} sr⁻¹", significant(v, 3)),
    };
    let mut out = format!(
        "retro lobe moments (Belcour et al. 2014 §3.D): {kept}, about the retro direction; angles in degrees\n\
         r = (σ²max − σ²min)/σ²min, 0 when isotropic; kurtosis 3 for a normal lobe\n\
         {:>6}  {:<10}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>8}  {:>7}  {:>7}  {:>7}\n",
        "θi", "plane", "samples", "gap/σ", "μx", "μy", "σx", "σy", "r", "ρxy", "kurt x", "kurt y"
    );
    for e in entries {
        let head = format!("{:>5}°  {:<10}", e.theta_i_deg, e.parametrization.name());
        match (&e.moments, &e.missing) {
            (Some(m), _) => {
                // Angles to 0.01°, finer than any head's stage; r to 0.001,
                // fine enough for the 0.05 that tells isotropy.
                out += &format!(
                    "{head}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>8}  {:>7}  {:>7}  {:>7}{}{}\n",
                    m.samples,
                    figure(m.gap_sigma, 2),
                    figure(m.mean_deg[0], 2),
                    figure(m.mean_deg[1], 2),
                    figure(m.sigma_deg[0], 2),
                    figure(m.sigma_deg[1], 2),
                    figure(m.r, 3),
                    figure(m.correlation, 2),
                    figure(m.kurtosis[0], 2),
                    figure(m.kurtosis[1], 2),
                    if m.under_sampled { "  *" } else { "" },
                    if m.truncated {
                        "  (truncated: the lobe reaches the edge of the data)"
                    } else {
                        ""
                    }
                );
            }
            (None, why) => out += &format!("{head}  none: {}\n", why.as_deref().unwrap_or_default()),
        }
    }
    if entries.iter().filter_map(|e| e.moments.as_ref()).any(|m| m.under_sampled) {
        out += "* samples more than a lobe width apart (gap/σ > 1): the lobe's outline and r follow the sampling";
        out += if this_head {
            " (the head's blind zone lies 5°–11.5° from the laser); a higher --threshold keeps the lobe within the retro rings\n"
        } else {
            "; a higher --threshold keeps the lobe where the samples are dense\n"
        };
    }
    if entries.iter().any(|e| e.mirrored) {
        out += "Δφ < 0 completed from Δφ > 0 by the isotropic BRDF's symmetry\n";
    }
    out
}
