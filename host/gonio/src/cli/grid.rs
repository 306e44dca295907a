//! Scan grids on the command line: `--theta-i 15,30,60 --theta-o 0:90:3 --dphi -180:180:10`.

use anyhow::{bail, Context, Result};
use gonio_analysis::coefficients::scan::measure_for;
use gonio_analysis::coefficients::Set;
use gonio_analysis::{fit, lobe};
use gonio_shared::lobe_pattern::{AZIMUTHS_MAX, RADIUS_MAX_DEG, RINGS_MAX};
use gonio_shared::{AngleRange, LobePatterns, Rings, ScanSpec, SweepLobe, SweepRequest, SweepScan};
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

impl Default for PatternArgs {
    fn default() -> Self {
        let p = LobePatterns::cea();
        PatternArgs {
            retro_rings: p.retro.radii_deg.to_vec(),
            retro_azimuths: p.retro.azimuths,
            mirror_rings: p.mirror.radii_deg.to_vec(),
            mirror_azimuths: p.mirror.azimuths,
            no_patterns: false,
        }
    }
}

impl PatternArgs {
    /// The patterns asked for, checked.
    pub fn patterns(&self) -> Result<Option<LobePatterns>> {
        if self.no_patterns {
            return Ok(None);
        }
        let rings = |radii: &[f32], azimuths: u16, what: &str| -> Result<Rings> {
            let r = Rings {
                radii_deg: heapless::Vec::from_slice(radii)
                    .ok()
                    .with_context(|| format!("--{what}-rings: at most {RINGS_MAX} rings"))?,
                azimuths,
            };
            if r.count().is_none() {
                bail!("--{what}-rings / --{what}-azimuths: radii in (0°, {RADIUS_MAX_DEG}°] and 1–{AZIMUTHS_MAX} views a ring");
            }
            Ok(r)
        };
        Ok(Some(LobePatterns {
            retro: rings(&self.retro_rings, self.retro_azimuths, "retro")?,
            mirror: rings(&self.mirror_rings, self.mirror_azimuths, "mirror")?,
        }))
    }
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

/// What a swept sample near a lobe's peak spans by default, over the lobe's
/// width: a quarter, so that a Gaussian lobe's sample is blurred by
/// `(e/σ)²/24`, 0.26 % at its peak, before the extent correction
/// (`calibration::unblur`) takes most of that away.
pub const SWEEP_EXTENT: f32 = 0.25;

impl LobeArgs {
    /// The lobe a sweep scan at incidences `theta_i_deg` slows down for, if any.
    pub fn lobe(&self, theta_i_deg: &[f32]) -> Result<Option<SweepLobe>> {
        let width_deg = match (self.sweep_lobe, &self.sweep_lobe_from) {
            (Some(w), _) => w,
            (None, Some(path)) => lobe::narrowest_deg(&fit::file::read_material(path)?, theta_i_deg)
                .with_context(|| format!("--sweep-lobe-from {}", path.display()))? as f32,
            (None, None) => return Ok(None),
        };
        let l = SweepLobe {
            width_deg,
            extent_fraction: self.sweep_extent,
        };
        if !l.valid() {
            bail!(
                "sweep lobe {width_deg}° with --sweep-extent {}: the width must lie in {}–90°, the extent in (0, 1]",
                self.sweep_extent,
                SweepLobe::WIDTH_MIN_DEG
            );
        }
        Ok(Some(l))
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
    pub fn spec(&self) -> Result<ScanSpec> {
        let theta_i_deg = heapless::Vec::from_slice(&self.theta_i)
            .ok()
            .context("--theta-i: at most 8 incidence angles")?;
        if let Some(t) = self.theta_i.iter().find(|t| !(0.0..90.0).contains(*t)) {
            bail!("--theta-i: {t}° is not an incidence the head can light (0° to under 90°)");
        }
        let (o, p) = (&self.theta_o, &self.dphi);
        if o.start_deg < 0.0 || o.stop_deg > 90.0 {
            bail!(
                "--theta-o: {}°:{}° reaches beyond the view angles 0° to 90°",
                o.start_deg,
                o.stop_deg
            );
        }
        if p.start_deg < -360.0 || p.stop_deg > 360.0 {
            bail!("--dphi: {}°:{}° reaches beyond −360° to 360°", p.start_deg, p.stop_deg);
        }
        let sweep = match self.sweep {
            true => Some(SweepScan {
                speed_dps: self.sweep_speed,
                periods_per_sample: self.sweep_periods,
                lobe: self.lobe.lobe(&theta_i_deg)?,
            }),
            false => None,
        };
        let mut spec = ScanSpec {
            theta_i_deg,
            theta_o: self.theta_o,
            dphi: self.dphi,
            first_order: 0,
            sweep,
            patterns: self.patterns.patterns()?,
        };
        measure_for(&mut spec, &self.for_sets)?;
        if let Some(a) = spec
            .asked()
            .filter(|a| spec.sweep.is_none() && a.positions() > u64::from(ScanSpec::POSITIONS_MAX))
        {
            bail!(
                "{} incidences × ({} θo × {} Δφ + {} pattern points) = {} positions: more than the {} a scan holds; take larger steps",
                a.incidences,
                a.theta_o,
                a.dphi,
                a.pattern_points,
                a.positions(),
                ScanSpec::POSITIONS_MAX
            );
        }
        spec.validate().map_err(|f| anyhow::anyhow!("grid refused: {f}"))?;
        Ok(spec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Grid {
        #[command(flatten)]
        grid: GridArgs,
    }

    fn grid(args: &[&str]) -> Result<ScanSpec> {
        let g = Grid::try_parse_from(std::iter::once("grid").chain(args.iter().copied()))?;
        g.grid.spec()
    }

    #[test]
    fn default_grid_is_belcour() {
        assert_eq!(grid(&[]).unwrap(), ScanSpec::belcour_with_patterns());
        assert_eq!(
            grid(&["--theta-i", "15,30,60", "--theta-o", "0:90:3", "--dphi", "-180:180:10"]).unwrap(),
            ScanSpec::belcour_with_patterns()
        );
        assert_eq!(ScanSpec::belcour().len(), 3 * 31 * 37);
        assert_eq!(ScanSpec::belcour_with_patterns().len(), 3 * (31 * 37 + 400));
    }

    #[test]
    fn bad_grids_are_refused_with_their_reason() {
        let refused = |args: &[&str], why: &str| {
            let e = grid(args).expect_err(&format!("{args:?}")).to_string();
            assert!(e.contains(why), "{args:?}: {e}");
        };
        refused(&["--theta-o", "0:90"], "not START:STOP:STEP");
        refused(&["--theta-o", "0:90:3:1"], "not START:STOP:STEP");
        refused(&["--theta-o", "0:90:0"], "empty or malformed");
        refused(&["--dphi", "0:x:1"], "finite numbers");
        refused(&["--dphi", "0:inf:1"], "finite numbers");
        refused(&["--theta-i", "x"], "not a number");
        refused(&["--theta-i", "nan"], "not finite");
        refused(&["--theta-i", "1,2,3,4,5,6,7,8,9"], "at most 8");
        refused(&["--theta-i", "100"], "not an incidence");
        refused(&["--theta-i", "-10"], "not an incidence");
        refused(&["--theta-o", "0:95:5"], "beyond the view angles");
        refused(&["--theta-o", "-5:60:5"], "beyond the view angles");
        refused(&["--dphi", "200:400:10"], "beyond −360° to 360°");
        refused(
            &["--theta-o", "0:80:0.0001", "--no-patterns"],
            "3 incidences × (800001 θo × 37 Δφ + 0 pattern points) = 88800111 positions: more than the 10000000 a scan holds",
        );
    }

    /// Every value of both sets lies on a pattern point of the scan `--for`
    /// makes, within what `gonio coefficients` calls measured.
    #[test]
    fn a_scan_for_the_standards_holds_every_geometry_they_name() {
        let spec = grid(&["--for", "astm-e810,en1436"]).unwrap();
        assert_eq!(spec.theta_i_deg.as_slice(), &[15.0, 30.0, 60.0, 4.0, 40.0, 45.0, 88.76]);
        let p = spec.patterns.as_ref().unwrap();
        assert_eq!(p.retro.radii_deg.len(), 11);
        let points: Vec<_> = (0..spec.len()).filter_map(|i| spec.point(i)).collect();
        for set in [Set::AstmE810, Set::En1436] {
            for r in set.requests() {
                let [ti, to, dp] = r.geometry.sample_angles_deg();
                let held = points.iter().any(|g| {
                    (g.theta_i_deg as f64 - ti).abs() < 0.01
                        && (g.theta_o_deg as f64 - to).abs() < 0.01
                        && (g.dphi_deg.abs() as f64 - dp).abs() < 0.01
                });
                assert!(held, "{set:?}: ({ti}, {to}, {dp}) is not a point of the scan");
            }
        }
        let refused = |args: &[&str], why: &str| {
            let e = grid(args).expect_err(&format!("{args:?}")).to_string();
            assert!(e.contains(why), "{args:?}: {e}");
        };
        refused(&["--for", "en1436", "--no-patterns"], "--no-patterns");
        refused(&["--for", "en1436", "--retro-azimuths", "7"], "even");
        refused(&["--for", "astm-e810", "--theta-i", "1,2,3,5,6"], "8 incidence");
    }

    #[test]
    fn bad_patterns_are_refused() {
        let p = |radii: Vec<f32>, az: u16| PatternArgs {
            retro_rings: radii,
            retro_azimuths: az,
            ..PatternArgs::default()
        };
        assert!(p(vec![0.0], 8).patterns().is_err());
        assert!(p(vec![1.0], 0).patterns().is_err());
        assert!(p(vec![1.0; 13], 8).patterns().is_err());
        assert!(p(vec![40.0], 8).patterns().is_err());
        assert_eq!(p(vec![1.0, 2.0], 8).patterns().unwrap().unwrap().count(), Some(16 + 80));
        let none = PatternArgs {
            no_patterns: true,
            ..PatternArgs::default()
        };
        assert_eq!(none.patterns().unwrap(), None);
    }
}
