//! Scan grids on the command line: `--theta-i 15,30,60 --theta-o 0:90:3 --dphi -180:180:10`.

use anyhow::{bail, Context, Result};
use gonio_shared::{AngleRange, ScanSpec, SweepRequest, SweepScan};

#[derive(Debug, Clone, clap::Args)]
pub struct GridArgs {
    /// Incidence angles θi (degrees), comma separated, at most 8.
    #[arg(long, value_name = "LIST", default_value = "15,30,60")]
    pub theta_i: String,
    /// View angles θo as START:STOP:STEP (degrees, STOP included).
    #[arg(long, value_name = "RANGE", default_value = "0:90:3", allow_hyphen_values = true)]
    pub theta_o: String,
    /// Azimuth differences Δφ as START:STOP:STEP (degrees, STOP included).
    #[arg(long, value_name = "RANGE", default_value = "-180:180:10", allow_hyphen_values = true)]
    pub dphi: String,
    /// Measure while moving: every (θi, Δφ) row swept over the θo span in
    /// one move, its samples tagged with where the stages were (the θo STEP
    /// is then unused).
    #[arg(long)]
    pub sweep: bool,
    /// Top speed of the arm in a sweep (deg/s), at most its limit (30 deg/s
    /// on the reference head): a sample spans this times its periods.
    #[arg(long, value_name = "DEG_PER_S", default_value_t = 30.0, requires = "sweep")]
    pub sweep_speed: f32,
    /// Chop periods per swept sample (4–8).
    #[arg(long, value_name = "N", default_value_t = SweepRequest::PERIODS_MAX, requires = "sweep")]
    pub sweep_periods: u16,
}

fn number(s: &str, what: &str) -> Result<f32> {
    let v: f32 = s.trim().parse().with_context(|| format!("{what}: `{s}` is not a number"))?;
    if !v.is_finite() {
        bail!("{what}: `{s}` is not finite");
    }
    Ok(v)
}

fn range(s: &str, what: &str) -> Result<AngleRange> {
    let parts: Vec<&str> = s.split(':').collect();
    let [a, b, c] = parts[..] else {
        bail!("{what}: `{s}` is not START:STOP:STEP");
    };
    let r = AngleRange::new(number(a, what)?, number(b, what)?, number(c, what)?);
    if r.count().is_none() {
        bail!("{what}: `{s}` is empty or malformed (STEP > 0, START ≤ STOP, span ≤ 360°)");
    }
    Ok(r)
}

impl GridArgs {
    pub fn spec(&self) -> Result<ScanSpec> {
        let mut theta_i_deg = heapless::Vec::new();
        for t in self.theta_i.split(',') {
            theta_i_deg
                .push(number(t, "--theta-i")?)
                .ok()
                .context("--theta-i: at most 8 incidence angles")?;
        }
        let spec = ScanSpec {
            theta_i_deg,
            theta_o: range(&self.theta_o, "--theta-o")?,
            dphi: range(&self.dphi, "--dphi")?,
            first_order: 0,
            sweep: self.sweep.then_some(SweepScan {
                speed_dps: self.sweep_speed,
                periods_per_sample: self.sweep_periods,
            }),
        };
        spec.validate().map_err(|f| anyhow::anyhow!("grid refused: {f}"))?;
        Ok(spec)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_grid_is_belcour() {
        let g = GridArgs {
            theta_i: "15,30,60".into(),
            theta_o: "0:90:3".into(),
            dphi: "-180:180:10".into(),
            sweep: false,
            sweep_speed: 30.0,
            sweep_periods: 8,
        };
        assert_eq!(g.spec().unwrap(), ScanSpec::belcour());
        assert_eq!(ScanSpec::belcour().len(), 3 * 31 * 37);
    }

    #[test]
    fn bad_grids_are_refused() {
        let g = |ti: &str, to: &str| {
            GridArgs {
                theta_i: ti.into(),
                theta_o: to.into(),
                dphi: "0:0:1".into(),
                sweep: false,
                sweep_speed: 30.0,
                sweep_periods: 8,
            }
            .spec()
        };
        assert!(g("15", "0:90").is_err());
        assert!(g("15", "0:90:0").is_err());
        assert!(g("x", "0:90:3").is_err());
        assert!(g("1,2,3,4,5,6,7,8,9", "0:90:3").is_err());
        assert!(g("nan", "0:90:3").is_err());
    }
}
