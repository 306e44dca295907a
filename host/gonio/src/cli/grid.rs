//! Scan grids on the command line: `--theta-i 15,30,60 --theta-o 0:90:3 --dphi -180:180:10`.

use anyhow::{Context, Result};
use gonio_acquire::grid::{Grid, Patterns, Sweep, SWEEP_EXTENT};
use gonio_analysis::coefficients::scan::measure_for;
use gonio_analysis::coefficients::Set;
use gonio_analysis::{fit, lobe};
use gonio_shared::{AngleRange, ScanSpec, SweepLobe, SweepRequest};
use std::path::PathBuf;

#[derive(Debug, Clone, clap::Args)]
pub struct GridArgs {
    /// Incidence angles θi (degrees), comma separated, at most 8.
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "15,30,60", value_parser = finite_deg, allow_hyphen_values = true)]
    pub theta_i: Vec<f32>,
    /// View angles θo as START:STOP:STEP (degrees, STOP included). The
    /// default is the Belcour grid as the paper gives it: its θo = 90°
    /// (grazing) is refused by the head, and counted as unreachable.
    #[arg(long, value_name = "RANGE", default_value = "0:90:3", allow_hyphen_values = true)]
    pub theta_o: AngleRange,
    /// Azimuth differences Δφ as START:STOP:STEP (degrees, STOP included).
    #[arg(long, value_name = "RANGE", default_value = "-180:180:10", allow_hyphen_values = true)]
    pub dphi: AngleRange,
    /// Measure while moving: a row per θi and Δφ value, each swept over the
    /// θo span in one move, its samples tagged with where the stages were
    /// (the θo STEP is then unused); the rows of a θi turned evenly about
    /// the laser between those meeting the horizon at the first and last Δφ
    /// (the Δφ STEP apart for the whole circle), and its retro point
    /// measured at rest.
    #[arg(long)]
    pub sweep: bool,
    /// Top speed of the arm in a sweep (deg/s), at most its limit (30 deg/s
    /// on the reference head): a sample spans this times its periods.
    #[arg(long, value_name = "DEG_PER_S", default_value_t = 30.0, requires = "sweep")]
    pub sweep_speed: f32,
    /// Chop periods per swept sample (4–8).
    #[arg(long, value_name = "N", default_value_t = SweepRequest::PERIODS_MAX, requires = "sweep")]
    pub sweep_periods: u16,
    #[command(flatten)]
    pub lobe: LobeArgs,
    #[command(flatten)]
    pub patterns: PatternArgs,
    /// Also measure what these sets of coefficients need (`gonio
    /// coefficients --set`): their incidences added to --theta-i, their
    /// observation angles to --retro-rings, so that every value of the set
    /// is `measured` (astm-e810: θi 4°, 40°, 45° and the rings it has;
    /// en1436: θi 88.76° and a 1.05° ring).
    #[arg(long = "for", value_name = "SET", value_enum, value_delimiter = ',')]
    pub for_sets: Vec<Set>,
}

/// The rings measured about the retro and the mirror direction of each
/// incidence besides the grid (`docs/optics.md`): the retro rings within the
/// head's through-splitter zone (5° on the reference head) are what a
/// coefficient of retroreflection at α ≤ 5° rests on.
#[derive(Debug, Clone, clap::Args)]
pub struct PatternArgs {
    /// Radii α of the rings about the retro direction (degrees, at most 12).
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        default_value = "0.1,0.2,0.33,0.5,1,1.5,2,3,4,4.75"
    )]
    pub retro_rings: Vec<f32>,
    /// Views on each retro ring, evenly around the laser.
    #[arg(long, value_name = "N", default_value_t = 32)]
    pub retro_azimuths: u16,
    /// Radii of the rings about the mirror direction (degrees, at most 10).
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "1,2,3,4.5,6")]
    pub mirror_rings: Vec<f32>,
    /// Views on each mirror ring.
    #[arg(long, value_name = "N", default_value_t = 16)]
    pub mirror_azimuths: u16,
    /// The grid (or the rows) alone, without the rings.
    #[arg(long, conflicts_with_all = ["retro_rings", "retro_azimuths", "mirror_rings", "mirror_azimuths"])]
    pub no_patterns: bool,
}

/// How a sweep slows down across the material's narrow lobes
/// ([`SweepLobe`]): near the retro and the mirror direction a swept sample
/// spans at most a set fraction of the lobe's width.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct LobeArgs {
    /// Slow a sweep down across the retro and mirror lobes, this wide (deg:
    /// where a lobe falls to e^(-1/2) of its height, 1/√n rad for a cosine
    /// lobe to the power n).
    #[arg(long, value_name = "DEG", requires = "sweep", conflicts_with = "sweep_lobe_from")]
    pub sweep_lobe: Option<f32>,
    /// Slow a sweep down across the lobes of a fitted model (a `gonio fit
    /// --out` file, say of a quick scan): as wide as its narrowest at the
    /// scan's incidences.
    #[arg(long, value_name = "FIT_JSON", requires = "sweep")]
    pub sweep_lobe_from: Option<PathBuf>,
    /// Largest angle a swept sample spans within three widths of a lobe's
    /// peak, over the lobe's width.
    #[arg(long, value_name = "F", default_value_t = SWEEP_EXTENT, requires = "sweep")]
    pub sweep_extent: f32,
}

impl LobeArgs {
    /// The lobe a sweep scan at incidences `theta_i_deg` slows down for, if any.
    pub fn lobe(&self, theta_i_deg: &[f32]) -> Result<Option<SweepLobe>> {
        let width_deg = match (self.sweep_lobe, &self.sweep_lobe_from) {
            (Some(w), _) => w,
            (None, Some(path)) => lobe::narrowest_deg(&fit::file::read_material(path)?, theta_i_deg)
                .with_context(|| format!("--sweep-lobe-from {}", path.display()))? as f32,
            (None, None) => return Ok(None),
        };
        Ok(Some(SweepLobe {
            width_deg,
            extent_fraction: self.sweep_extent,
        }))
    }
}

/// An angle in degrees, finite.
fn finite_deg(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("`{s}` is not finite")),
        Err(_) => Err(format!("`{s}` is not a number")),
    }
}

impl GridArgs {
    /// The scan these flags ask for, with what `--for`'s sets need.
    pub fn scan_spec(&self) -> Result<ScanSpec> {
        let p = &self.patterns;
        let grid = Grid {
            theta_i_deg: self.theta_i.clone(),
            theta_o: self.theta_o,
            dphi: self.dphi,
            sweep: match self.sweep {
                true => Some(Sweep {
                    speed_dps: self.sweep_speed,
                    periods_per_sample: self.sweep_periods,
                    lobe: self.lobe.lobe(&self.theta_i)?,
                }),
                false => None,
            },
            patterns: (!p.no_patterns).then(|| Patterns {
                retro_radii_deg: p.retro_rings.clone(),
                retro_azimuths: p.retro_azimuths,
                mirror_radii_deg: p.mirror_rings.clone(),
                mirror_azimuths: p.mirror_azimuths,
            }),
        };
        grid.scan_spec(|spec| measure_for(spec, &self.for_sets))
    }
}
