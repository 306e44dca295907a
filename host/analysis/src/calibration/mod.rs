//! From raw samples to BRDF (Zhang eq. 7–8): the
//! photocurrent `I = V/G` (gain ranges normalised by the head's gain in V/A)
//! is `K·P(t)·f_r·cosθo·T`, with `K` the detector's scale, `P(t)` the laser
//! power relative to a reference time, and `T` the beam splitter's factor for
//! samples taken through it (1 elsewhere).
//!
//! - A reference-plate run (Lambertian, `f_r = ρ_ref/π`) gives `K` from its
//!   samples outside the splitter zone and `T` from those inside it.
//! - Each run's laser-drift monitor (`gonio scan --monitor`, rows without a
//!   scan position) gives `P(t)`, interpolated smoothly between readings;
//!   both runs are referred to the plate's last reading. The head's clock
//!   runs on between the two (timestamps since power-up), so the sample's
//!   drift curve is extended back to that instant by a straight line through
//!   its first readings: swapping the plate and homing again take minutes,
//!   over which the laser drifts too.
//! - Every value carries its uncertainty budget (`crate::uncertainty`):
//!   the sample's own noise, the plate's certificate, `K`'s and `T`'s spread
//!   over the plate, the monitor's, the gain ranges, stray light, and the
//!   stage angles' errors times the local slope of the BRDF (from a smooth
//!   model fitted to the same data: only its slope is used).

pub mod directory;
mod text;
mod unblur;

use crate::fit::{Dataset, Observation, Units};
use crate::uncertainty::{Components, HeadUncertainty, K_COVERAGE, SHARED};
use anyhow::{bail, Result};
use gonio_brdf::{Directions, Material};
use gonio_scan_dir::calibrated;
use gonio_scan_dir::samples::Row;
use gonio_shared::SampleFlags;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Samples whose value is not a measurement of the BRDF.
const UNUSABLE: SampleFlags = SampleFlags::SATURATED
    .union(SampleFlags::OVERRUN)
    .union(SampleFlags::PHASE_OFF)
    .union(SampleFlags::BELOW_NOISE);

pub fn usable(r: &Row) -> bool {
    !r.sample_flags().intersects(UNUSABLE)
}

fn current_a(r: &Row) -> f64 {
    r.amplitude_v as f64 / r.gain_v_per_a as f64
}

fn through_splitter(r: &Row) -> bool {
    r.sample_flags().contains(SampleFlags::THROUGH_SPLITTER)
}

fn cos_o(r: &Row) -> f64 {
    (r.theta_o_deg as f64).to_radians().cos()
}

/// Relative laser power through a run, from its monitor readings.
#[derive(Debug, Clone, PartialEq)]
pub struct Drift {
    /// `(t, photocurrent)` of the readings, sorted by time.
    readings: Vec<(f64, f64)>,
    /// Reading (photocurrent) the power is referred to.
    reference: f64,
    /// Relative standard uncertainty of one reading.
    pub rel_sd: f64,
}

/// Readings closer than this (s) belong to one visit of the monitor.
const VISIT_GAP_S: f64 = 30.0;

/// Readings this close to the first one (s) set the line the drift is
/// extended back along.
const EXTRAPOLATION_SPAN_S: f64 = 600.0;

impl Drift {
    /// From monitor readings, referred to the power at time `anchor`
    /// (default: the last reading). No readings: no correction.
    pub fn from_monitor(rows: &[Row], anchor: Option<f64>) -> Drift {
        let mut m: Vec<(f64, f64, f64)> = rows
            .iter()
            .filter(|r| usable(r))
            .map(|r| (r.timestamp_s, current_a(r), r.noise_v as f64 / r.amplitude_v as f64))
            .collect();
        m.sort_by(|a, b| a.0.total_cmp(&b.0));
        // One visit's readings, seconds apart, are one point of the curve.
        let mut visits: Vec<Vec<(f64, f64, f64)>> = Vec::new();
        for r in m {
            match visits.last_mut() {
                Some(v) if r.0 - v[v.len() - 1].0 < VISIT_GAP_S => v.push(r),
                _ => visits.push(vec![r]),
            }
        }
        let mean = |v: &[(f64, f64, f64)], f: fn(&(f64, f64, f64)) -> f64| v.iter().map(f).sum::<f64>() / v.len() as f64;
        let mut noise: Vec<f64> = visits.iter().map(|v| mean(v, |x| x.2) / (v.len() as f64).sqrt()).collect();
        noise.sort_by(f64::total_cmp);
        let mut d = Drift {
            readings: visits.iter().map(|v| (mean(v, |x| x.0), mean(v, |x| x.1))).collect(),
            reference: 1.0,
            // An interpolated ratio of two visits.
            rel_sd: noise.get(noise.len() / 2).copied().unwrap_or(0.0) * std::f64::consts::SQRT_2,
        };
        if let Some(&(t_last, _)) = d.readings.last() {
            d.reference = d.raw(anchor.unwrap_or(t_last));
        }
        d
    }

    pub fn readings(&self) -> usize {
        self.readings.len()
    }

    /// Time of the last reading.
    pub fn last_time(&self) -> Option<f64> {
        self.readings.last().map(|r| r.0)
    }

    /// Photocurrent of the monitor at `t`: a cubic between readings, constant
    /// after the last, and before the first along the least-squares line
    /// through the readings of the first [`EXTRAPOLATION_SPAN_S`].
    fn raw(&self, t: f64) -> f64 {
        let p = &self.readings;
        match p.iter().position(|&(tk, _)| tk >= t) {
            None => p.last().map_or(1.0, |x| x.1),
            Some(0) => {
                let early: Vec<(f64, f64)> = p.iter().copied().take_while(|x| x.0 <= p[0].0 + EXTRAPOLATION_SPAN_S).collect();
                if early.len() < 2 {
                    return p[0].1;
                }
                let n = early.len() as f64;
                let (mt, mi) = (
                    early.iter().map(|x| x.0).sum::<f64>() / n,
                    early.iter().map(|x| x.1).sum::<f64>() / n,
                );
                let sxx: f64 = early.iter().map(|x| (x.0 - mt) * (x.0 - mt)).sum();
                let sxy: f64 = early.iter().map(|x| (x.0 - mt) * (x.1 - mi)).sum();
                mi + sxy / sxx * (t - mt)
            }
            Some(k) => {
                // Cubic Hermite between the two readings around `t`, with
                // Catmull–Rom slopes: a drifting laser is smooth, and a
                // straight line through readings minutes apart misses its
                // curvature (measured: median error 0.5 % → 0.2 % at ±5 %).
                let ((t0, a), (t1, b)) = (p[k - 1], p[k]);
                let slope = |j: usize| {
                    let (lo, hi) = (j.saturating_sub(1), (j + 1).min(p.len() - 1));
                    (p[hi].1 - p[lo].1) / (p[hi].0 - p[lo].0)
                };
                let h = t1 - t0;
                let u = (t - t0) / h;
                let (u2, u3) = (u * u, u * u * u);
                (2.0 * u3 - 3.0 * u2 + 1.0) * a
                    + (u3 - 2.0 * u2 + u) * h * slope(k - 1)
                    + (-2.0 * u3 + 3.0 * u2) * b
                    + (u3 - u2) * h * slope(k)
            }
        }
    }

    /// Laser power at `t` relative to the anchor.
    pub fn at(&self, t: f64) -> f64 {
        if self.readings.is_empty() {
            1.0
        } else {
            self.raw(t) / self.reference
        }
    }

    /// Smallest and largest relative power over the readings.
    pub fn range(&self) -> (f64, f64) {
        self.readings
            .iter()
            .map(|&(t, _)| self.at(t))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    }
}

/// The result of a reference-plate run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    pub rho_ref: f64,
    /// Standard uncertainty of `rho_ref` (the plate's certificate).
    #[serde(default)]
    pub rho_ref_u: f64,
    /// `K`: photocurrent per unit `f_r·cosθo` at the reference laser power (A·sr).
    pub scale_a_sr: f64,
    pub scale_rel_sd: f64,
    /// `T`, the beam splitter's factor on the retro path.
    pub splitter: f64,
    pub splitter_rel_sd: f64,
    /// Whether `T` was measured on the plate (else given by the user).
    pub splitter_measured: bool,
    pub reference_samples: usize,
    pub reference_monitor_readings: usize,
    /// Head time (s) of the plate run's last monitor reading: the instant
    /// the laser power is referred to.
    pub reference_time_s: Option<f64>,
}

fn mean_and_rel_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    if v.len() < 2 {
        return (mean, 0.0);
    }
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt() / mean)
}

impl Calibration {
    /// From the plate's samples and the monitor readings taken with it (none
    /// for the few points of `gonio scan --reference-plate`). `splitter` is
    /// used only when no plate sample was taken through the splitter.
    pub fn from_plate(plate: &[Row], monitor: &[Row], rho_ref: f64, rho_ref_u: f64, splitter: Option<f64>) -> Result<Calibration> {
        if !(rho_ref > 0.0 && rho_ref <= 1.0) {
            bail!("ρ_ref = {rho_ref} must be in (0, 1]");
        }
        if !(rho_ref_u >= 0.0 && rho_ref_u < rho_ref) {
            bail!("the uncertainty of ρ_ref ({rho_ref_u}) must be in [0, ρ_ref)");
        }
        let drift = Drift::from_monitor(monitor, None);
        let f_ref = rho_ref / PI;
        let normalised = |r: &Row| current_a(r) / (drift.at(r.timestamp_s) * f_ref * cos_o(r));
        let plate: Vec<&Row> = plate.iter().filter(|r| usable(r)).collect();
        let outside: Vec<f64> = plate.iter().filter(|r| !through_splitter(r)).map(|r| normalised(r)).collect();
        if outside.is_empty() {
            bail!("the reference run has no usable sample outside the beam splitter's zone: cannot set the scale");
        }
        let (scale, scale_rel_sd) = mean_and_rel_se(&outside);
        let inside: Vec<f64> = plate
            .iter()
            .filter(|r| through_splitter(r))
            .map(|r| normalised(r) / scale)
            .collect();
        let (splitter, splitter_rel_sd, splitter_measured) = match (inside.is_empty(), splitter) {
            (false, _) => {
                let (t, sd) = mean_and_rel_se(&inside);
                (t, sd, true)
            }
            (true, Some(t)) if t > 0.0 && t <= 1.0 => (t, 0.0, false),
            (true, Some(t)) => bail!("--splitter {t} must be in (0, 1]"),
            (true, None) => bail!("the reference run has no sample through the beam splitter: give --splitter"),
        };
        Ok(Calibration {
            rho_ref,
            rho_ref_u,
            scale_a_sr: scale,
            scale_rel_sd: (scale_rel_sd * scale_rel_sd + drift.rel_sd * drift.rel_sd).sqrt(),
            splitter,
            splitter_rel_sd,
            splitter_measured,
            reference_samples: plate.len(),
            reference_monitor_readings: drift.readings(),
            reference_time_s: drift.last_time().or_else(|| plate.iter().map(|r| r.timestamp_s).reduce(f64::max)),
        })
    }

    /// Calibrated rows of a sample run (scan positions only), in its order,
    /// each with its uncertainty budget. Its monitor is referred to the
    /// plate's last reading when the two share a clock (the sample run starts
    /// after it); otherwise to its own first reading.
    pub fn apply(&self, rows: &[Row], budget: &Budget) -> (Vec<CalibratedRow>, Drift) {
        let first_sample = rows.iter().map(|r| r.timestamp_s).fold(f64::INFINITY, f64::min);
        let anchor = match self.reference_time_s {
            Some(t) if t <= first_sample => Some(t),
            _ => rows.iter().filter(|r| r.index.is_none()).map(|r| r.timestamp_s).reduce(f64::min),
        };
        let monitor: Vec<Row> = rows.iter().filter(|r| r.index.is_none()).cloned().collect();
        let drift = Drift::from_monitor(&monitor, anchor);
        let head = &budget.head;
        let mut out = rows
            .iter()
            .filter(|r| r.index.is_some())
            .map(|r| {
                let d = drift.at(r.timestamp_s);
                let t = if through_splitter(r) { self.splitter } else { 1.0 };
                let fr_cos = current_a(r) / (d * self.scale_a_sr * t);
                let fr = fr_cos / cos_o(r);
                let f = fr.abs();
                let noise = r.noise_v as f64 / r.amplitude_v.abs().max(f32::MIN_POSITIVE) as f64;
                let split = if through_splitter(r) { self.splitter_rel_sd } else { 0.0 };
                let slopes = budget.slope.as_ref().map_or([0.0; 3], |m| stage_slopes(m, r));
                let u = Components {
                    noise: f * noise,
                    rho_ref: f * self.rho_ref_u / self.rho_ref,
                    scale: f * self.scale_rel_sd,
                    splitter: f * split,
                    drift: f * drift.rel_sd,
                    gain: f * head.gain_ratio_rel(),
                    angle: (0..3).map(|a| (slopes[a] * head.axis_deg(a)).powi(2)).sum::<f64>().sqrt(),
                    stray: head.stray_u_a() / (d * self.scale_a_sr * t * cos_o(r)),
                };
                // A higher plate reflectance raises every value, a higher K lowers it.
                let shifts = [
                    u.rho_ref,
                    -u.scale,
                    slopes[0] * head.zero_deg[0],
                    slopes[1] * head.zero_deg[1],
                    slopes[2] * head.zero_deg[2],
                ];
                CalibratedRow {
                    raw: r.clone(),
                    laser_power: d,
                    usable: usable(r),
                    brdf_sr: fr,
                    brdf_sigma_sr: u.combined(),
                    brdf_cos_sr: fr_cos,
                    budget: u,
                    shifts,
                }
            })
            .collect::<Vec<_>>();
        unblur::unblur(&mut out);
        (out, drift)
    }
}

/// What a calibration states about the head beyond the plate: its type-B
/// uncertainties, and the smooth model whose slope turns angle errors into
/// BRDF errors (none: no angle component).
#[derive(Debug, Clone, Default)]
pub struct Budget {
    pub head: HeadUncertainty,
    pub slope: Option<Material>,
}

/// Step of the central differences of the angle component (degrees): well
/// inside the narrowest lobe the models reach, well above f64 rounding.
const SLOPE_STEP_DEG: f64 = 1e-3;

/// How much a calibrated value moves per degree of each stage `a`'s error
/// (sr⁻¹ per degree): the head reads `f·cosθo` at the true angles and the
/// calibration divides by `cosθo` at the reported ones, so the slope is
/// `∂(f·cosθo)/∂a / cosθo`, the stage's angle moved through the head's
/// lab-frame geometry (`Directions::from_stage`) into the model's BRDF. The
/// second term, `f·tanθo·∂θo/∂a`, is what dominates at a grazing view: at
/// EN 1436's θo = 87.71° a 0.02° zero moves the value by 0.9 %.
fn stage_slopes(model: &Material, r: &Row) -> [f64; 3] {
    let at = [r.omega_deg as f64, r.tau_deg as f64, r.psi_deg as f64];
    let f = |a: [f64; 3]| Directions::from_stage(a).map(|d| model.eval(&d) * d.cos_o());
    let Some(cos_o) = Directions::from_stage(at).map(|d| d.cos_o()).filter(|c| *c > 0.0) else {
        return [0.0; 3];
    };
    [0, 1, 2].map(|axis| {
        let moved = |s: f64| {
            let mut a = at;
            a[axis] += s * SLOPE_STEP_DEG;
            f(a)
        };
        let reading = match (moved(1.0), moved(-1.0), f(at)) {
            (Some(p), Some(m), _) => (p - m) / (2.0 * SLOPE_STEP_DEG),
            (Some(p), None, Some(c)) => (p - c) / SLOPE_STEP_DEG,
            (None, Some(m), Some(c)) => (c - m) / SLOPE_STEP_DEG,
            _ => 0.0,
        };
        reading / cos_o
    })
}

/// The budget of one incidence angle: the median of each component
/// relative to the value, over its usable samples, largest first.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IncidenceBudget {
    pub theta_i_deg: f64,
    pub samples: usize,
    /// `(component, median relative standard uncertainty)`, largest first.
    pub components: Vec<(String, f64)>,
    /// Median relative combined standard uncertainty.
    pub combined: f64,
}

/// Per incidence angle (rounded to 0.1°), what the budget is made of.
pub fn budget_by_incidence(rows: &[CalibratedRow]) -> Vec<IncidenceBudget> {
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    };
    let incidence = |r: &CalibratedRow| (r.raw.target_theta_i_deg as f64 * 10.0).round() / 10.0;
    let mut angles: Vec<f64> = rows.iter().map(incidence).collect();
    angles.sort_by(f64::total_cmp);
    angles.dedup();
    angles
        .into_iter()
        .filter_map(|ti| {
            let at: Vec<&CalibratedRow> = rows.iter().filter(|r| r.usable && r.brdf_sr != 0.0 && incidence(r) == ti).collect();
            if at.is_empty() {
                return None;
            }
            let rel = |k: usize| median(at.iter().map(|r| r.budget.values()[k] / r.brdf_sr.abs()).collect());
            let mut components: Vec<(String, f64)> = Components::NAMES.iter().enumerate().map(|(k, n)| (n.to_string(), rel(k))).collect();
            components.sort_by(|a, b| b.1.total_cmp(&a.1));
            Some(IncidenceBudget {
                theta_i_deg: ti,
                samples: at.len(),
                components,
                combined: median(at.iter().map(|r| r.brdf_sigma_sr / r.brdf_sr.abs()).collect()),
            })
        })
        .collect()
}

/// The usable calibrated values as a data set in `f_r`, each with its
/// uncertainty and the shifts of the inputs every sample shares.
pub fn dataset(rows: &[CalibratedRow]) -> Dataset {
    Dataset {
        units: Units::Fr,
        observations: rows
            .iter()
            .filter(|r| r.usable)
            .map(|r| Observation {
                theta_i: (r.raw.theta_i_deg as f64).to_radians(),
                theta_o: (r.raw.theta_o_deg as f64).to_radians(),
                dphi: (r.raw.dphi_deg as f64).to_radians(),
                value: r.brdf_sr,
                sigma: Some(r.brdf_sigma_sr).filter(|s| *s > 0.0),
                shared: r.shifts,
            })
            .collect(),
        metadata: Vec::new(),
        units_stated: true,
        warnings: Vec::new(),
        instrument: crate::instrument::Instrument::ThisHead,
    }
}

/// A raw row with its calibrated value beside it (`calibrated.csv`).
#[derive(Debug, Clone, PartialEq)]
pub struct CalibratedRow {
    pub raw: Row,
    /// Laser power relative to the plate's, from the monitor.
    pub laser_power: f64,
    /// False where a flag says the value is not a measurement (saturated, overrun, phase off, below noise).
    pub usable: bool,
    pub brdf_sr: f64,
    /// Combined standard uncertainty of `brdf_sr`.
    pub brdf_sigma_sr: f64,
    pub brdf_cos_sr: f64,
    /// The components `brdf_sigma_sr` combines.
    pub budget: Components,
    /// How much `brdf_sr` moves when each input every sample shares
    /// (`uncertainty::SHARED`) is off by one standard uncertainty (sr⁻¹).
    pub shifts: [f64; SHARED.len()],
}

/// Writes `calibrated.csv` ([`gonio_scan_dir::calibrated`]) under the
/// budget's component names and the shared inputs' names.
pub fn write_csv(path: &std::path::Path, rows: &[CalibratedRow]) -> Result<()> {
    let mut out = calibrated::Writer::create(path, &Components::NAMES, &SHARED)?;
    for r in rows {
        let components: Vec<f64> = r.budget.values().iter().chain(&r.shifts).copied().collect();
        let values = calibrated::Values {
            laser_power: r.laser_power,
            usable: r.usable,
            brdf_sr: r.brdf_sr,
            brdf_sigma_sr: r.brdf_sigma_sr,
            brdf_cos_sr: r.brdf_cos_sr,
            brdf_lo_sr: r.brdf_sr - K_COVERAGE * r.brdf_sigma_sr,
            brdf_hi_sr: r.brdf_sr + K_COVERAGE * r.brdf_sigma_sr,
            components: &components,
        };
        out.push(&r.raw, &values)?;
    }
    out.finish()
}
