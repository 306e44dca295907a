//! A scan grid as a user asks for it (incidences, view and azimuth ranges,
//! a sweep, the lobe rings), checked into the [`ScanSpec`] a head runs: each
//! refusal names the option at fault and why, before any head is touched.

use anyhow::{bail, Context, Result};
use gonio_shared::lobe_pattern::{AZIMUTHS_MAX, RADIUS_MAX_DEG, RINGS_MAX};
use gonio_shared::{AngleRange, LobePatterns, Rings, ScanSpec, SweepLobe, SweepScan};

/// The grid asked for, in degrees, before any check.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    pub theta_i_deg: Vec<f32>,
    pub theta_o: AngleRange,
    pub dphi: AngleRange,
    pub sweep: Option<Sweep>,
    /// The rings about the retro and mirror directions (`None`: the grid alone).
    pub patterns: Option<Patterns>,
}

/// A sweep as asked for: the arm's top speed, chop periods per sample, and
/// the lobe it slows down for.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    pub speed_dps: f32,
    pub periods_per_sample: u16,
    /// The narrowest lobe's width (deg) and the fraction of it a swept
    /// sample may span near its peak.
    pub lobe: Option<SweepLobe>,
}

/// The rings about the retro and the mirror direction of each incidence
/// (`docs/optics.md`), as lists.
#[derive(Debug, Clone, PartialEq)]
pub struct Patterns {
    pub retro_radii_deg: Vec<f32>,
    pub retro_azimuths: u16,
    pub mirror_radii_deg: Vec<f32>,
    pub mirror_azimuths: u16,
}

impl Default for Patterns {
    /// CEA's rings ([`LobePatterns::cea`]).
    fn default() -> Self {
        let p = LobePatterns::cea();
        Patterns {
            retro_radii_deg: p.retro.radii_deg.to_vec(),
            retro_azimuths: p.retro.azimuths,
            mirror_radii_deg: p.mirror.radii_deg.to_vec(),
            mirror_azimuths: p.mirror.azimuths,
        }
    }
}

impl Patterns {
    /// The patterns, checked.
    pub fn checked(&self) -> Result<LobePatterns> {
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
        Ok(LobePatterns {
            retro: rings(&self.retro_radii_deg, self.retro_azimuths, "retro")?,
            mirror: rings(&self.mirror_radii_deg, self.mirror_azimuths, "mirror")?,
        })
    }
}

/// What a swept sample near a lobe's peak spans by default, over the lobe's
/// width: a quarter, so that a Gaussian lobe's sample is blurred by
/// `(e/σ)²/24`, 0.26 % at its peak, before the extent correction
/// (`calibration::unblur`) takes most of that away.
pub const SWEEP_EXTENT: f32 = 0.25;

impl Grid {
    /// The scan this grid asks for, `widen`ed (say, by what a set of
    /// coefficients needs measured) before its size and the head's limits
    /// are checked.
    pub fn scan_spec(&self, widen: impl FnOnce(&mut ScanSpec) -> Result<()>) -> Result<ScanSpec> {
        let theta_i_deg = heapless::Vec::from_slice(&self.theta_i_deg)
            .ok()
            .context("--theta-i: at most 8 incidence angles")?;
        if let Some(t) = self.theta_i_deg.iter().find(|t| !(0.0..90.0).contains(*t)) {
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
        let sweep = match &self.sweep {
            Some(s) => Some(SweepScan {
                speed_dps: s.speed_dps,
                periods_per_sample: s.periods_per_sample,
                lobe: s.lobe.map(checked_lobe).transpose()?,
            }),
            None => None,
        };
        let mut spec = ScanSpec {
            theta_i_deg,
            theta_o: self.theta_o,
            dphi: self.dphi,
            first_order: 0,
            sweep,
            patterns: self.patterns.as_ref().map(Patterns::checked).transpose()?,
        };
        widen(&mut spec)?;
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

fn checked_lobe(l: SweepLobe) -> Result<SweepLobe> {
    if !l.valid() {
        bail!(
            "sweep lobe {}° with --sweep-extent {}: the width must lie in {}–90°, the extent in (0, 1]",
            l.width_deg,
            l.extent_fraction,
            SweepLobe::WIDTH_MIN_DEG
        );
    }
    Ok(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_patterns_are_refused() {
        let p = |radii: Vec<f32>, az: u16| Patterns {
            retro_radii_deg: radii,
            retro_azimuths: az,
            ..Patterns::default()
        };
        assert!(p(vec![0.0], 8).checked().is_err());
        assert!(p(vec![1.0], 0).checked().is_err());
        assert!(p(vec![1.0; 13], 8).checked().is_err());
        assert!(p(vec![40.0], 8).checked().is_err());
        assert_eq!(p(vec![1.0, 2.0], 8).checked().unwrap().count(), Some(16 + 80));
    }
}
