//! Where a coefficient's BRDF comes from, and how its uncertainty follows:
//! a model with its parameters' covariance (linear propagation; a Monte
//! Carlo check of it), measured data interpolated on the sphere, or both:
//! the data where they hold the geometry, the models fitted to them beyond
//! (with a term for how much models that fit alike disagree there).

use super::provenance::{Basis, Point, Provenance, Support};
use super::{aperture, Apertures, Cie, Request};
use crate::fit::file::FittedBrdf;
use crate::fit::goodness::{Adequacy, Goodness};
use crate::fit::Dataset;
use crate::instrument::Instrument;
use crate::uncertainty::HeadUncertainty;
use anyhow::{bail, Result};
use gonio_brdf::aperture::diameter_deg;
use gonio_brdf::frame::angle_between;
use gonio_brdf::{Directions, Material, Specimen};
use gonio_firmware::config::REFERENCE;
use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::Serialize;

/// The BRDF a coefficient is computed from.
#[derive(Debug, Clone)]
pub enum Source {
    /// A model; with a covariance (`gonio fit`'s: the samples' scatter and
    /// the inputs they share, the plate and the stage zeros) its parameters'
    /// uncertainty is propagated.
    Model {
        material: Material,
        covariance: Option<DMatrix<f64>>,
    },
    /// Measured values (`f_r`), interpolated between the nearest
    /// geometries; a geometry they do not hold is refused.
    Data { support: Support },
    /// Measured values and the models fitted to them (`gonio fit --out`
    /// files keep their data's support): where the data hold the geometry
    /// (measured, interpolated) the value is theirs, corrected to the
    /// standard's apertures with their own curvature; within the data's
    /// spacing, the best adequate model's, its uncertainty widened by the
    /// adequate models' spread; beyond it, or with no adequate model,
    /// nothing, unless `extrapolate` (`--extrapolate`) asks for a value.
    Measured {
        fits: Vec<Fitted>,
        support: Support,
        extrapolate: bool,
    },
    /// A simulated head's material itself (`gonio coefficients --material`):
    /// the truth a simulated scan's coefficients are checked against,
    /// through the same apertures, without uncertainty.
    Truth(Specimen),
}

/// A model or the rational function fitted to the data, and how well.
/// The rational function never carries a value beyond the data: it is held
/// by its segments only where there are samples (its denominator is kept
/// positive only there), so what it says beyond them is no measurement's,
/// and a wild value there would widen the models' spread for nothing.
#[derive(Debug, Clone)]
pub struct Fitted {
    pub brdf: FittedBrdf,
    /// The parameters' covariance (a model's only).
    pub covariance: Option<DMatrix<f64>>,
    /// Root mean square residual, in the data's units.
    pub rmse: f64,
    pub aic: f64,
    /// χ² against the data's σ: whether it may carry a value where the
    /// data end ([`Adequacy`]).
    pub goodness: Option<Goodness>,
}

impl From<&crate::fit::Fit> for Fitted {
    fn from(f: &crate::fit::Fit) -> Self {
        Fitted {
            brdf: FittedBrdf::Model(f.material.clone()),
            covariance: f.covariance.clone(),
            rmse: f.metrics.rmse,
            aic: f.aic,
            goodness: f.goodness,
        }
    }
}

/// Where no model is adequate and the user asked for an extrapolation all
/// the same (`--extrapolate`), the models whose RMSE is within this factor
/// of the best one's carry it together: what the data cannot tell apart,
/// their spread the model term. A statement about the models at hand, not
/// a verdict on any of them.
pub const COMPARABLE_RMSE_RATIO: f64 = 2.0;

/// The reference head's apertures: a collimated laser (a point source) and
/// a detector field of `ArmOptics::detector_sr` (a disc 0.39° across),
/// which a measured value is the average over.
pub fn head_apertures() -> Apertures {
    Apertures {
        source_deg: 0.0,
        receiver_deg: diameter_deg(REFERENCE.optics.detector_sr as f64),
    }
}

/// A measured geometry a data-interpolated coefficient leaned on.
#[derive(Debug, Clone, Serialize)]
pub struct Nearest {
    pub theta_i_deg: f64,
    pub theta_o_deg: f64,
    pub dphi_deg: f64,
    /// Angular distance from the requested geometry (degrees, both directions).
    pub distance_deg: f64,
    pub weight: f64,
    pub brdf_sr: f64,
    /// How much it moves with the arm's zero (the calibration's estimate).
    #[serde(skip)]
    pub shift_psi: f64,
}

/// A value, its standard uncertainty, and what the uncertainty is made of.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Estimate {
    /// NaN where the data cannot give one (a geometry they do not hold,
    /// with no model): printed as refused, `null` in JSON.
    pub value: f64,
    pub u: f64,
    /// Part of `u` from the model's parameters (linear propagation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub u_params: Option<f64>,
    /// Part of `u` from the models' disagreement (half the range of the
    /// adequate models' values) where a model carries the value.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub u_model: Option<f64>,
    /// Part of `u` from carrying a measured value from the head's
    /// apertures to the standard's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub u_aperture: Option<f64>,
    /// Part of `u` from the arm's zero, from the measured samples' own slope.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub u_arm_zero: Option<f64>,
    /// What the value rests on, when the source has data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub basis: Option<Basis>,
    /// The model that carries an extrapolated value, and every adequate
    /// model's value there.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model: Option<&'static str>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub models: Vec<ModelValue>,
    /// The measured geometries behind a value interpolated from data.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub nearest: Vec<Nearest>,
}

/// One adequate model's value of a coefficient.
#[derive(Debug, Clone, Serialize)]
pub struct ModelValue {
    pub model: &'static str,
    pub value: f64,
    pub rmse: f64,
}

/// How many measured geometries an interpolated value leans on.
const NEIGHBOURS: usize = 4;

/// Directions with the view folded onto `Δφ ≥ 0`.
fn folded(d: &Directions) -> Directions {
    Directions {
        l: d.l,
        v: [d.v[0], d.v[1].abs(), d.v[2]],
    }
}

impl Source {
    /// A model without uncertainty.
    pub fn model(material: Material) -> Self {
        Source::Model {
            material,
            covariance: None,
        }
    }

    /// Measured values. Values in `f_r·cosθo` are converted to `f_r`.
    pub fn data(data: &Dataset) -> Result<Self> {
        if data.observations.is_empty() {
            bail!("no measured values to interpolate");
        }
        Ok(Source::Data {
            support: Support::of(data)?,
        })
    }

    /// Measured values and the models fitted to them (at least one); no
    /// value where only a model would carry it beyond the data's spacing or
    /// without an adequate model (see [`Source::extrapolating`]).
    pub fn measured(fits: Vec<Fitted>, support: Support) -> Result<Self> {
        if fits.is_empty() {
            bail!("no fitted model");
        }
        Ok(Source::Measured {
            fits,
            support,
            extrapolate: false,
        })
    }

    /// What measured the values a coefficient may rest on: the data's
    /// instrument; this head for a simulated material; none for a model.
    pub fn instrument(&self) -> Option<Instrument> {
        match self {
            Source::Data { support } | Source::Measured { support, .. } => Some(support.instrument),
            Source::Truth(_) => Some(Instrument::ThisHead),
            Source::Model { .. } => None,
        }
    }

    /// The same source, computing the values the data cannot support from
    /// the models all the same (`--extrapolate`), each marked.
    pub fn extrapolating(self, on: bool) -> Self {
        match self {
            Source::Measured { fits, support, .. } => Source::Measured {
                fits,
                support,
                extrapolate: on,
            },
            other => other,
        }
    }

    /// The coefficient and its standard uncertainty.
    pub fn estimate(&self, r: &Request) -> Result<Estimate> {
        match self {
            Source::Model { material, covariance } => {
                let value = model_value(material, r);
                let u_params = covariance.as_ref().map(|c| linear_u(material, c, |m| model_value(m, r)));
                Ok(Estimate {
                    value,
                    u: u_params.unwrap_or(0.0),
                    u_params,
                    ..Estimate::default()
                })
            }
            Source::Data { support } => {
                let basis = support.classify(&r.geometry.directions(), r.apertures.widest());
                if !basis.provenance.on_data() {
                    return Ok(Estimate {
                        value: f64::NAN,
                        u: f64::NAN,
                        basis: Some(basis),
                        ..Estimate::default()
                    });
                }
                Ok(Estimate {
                    basis: Some(basis),
                    ..carried(support, r, interpolate(&support.points, r))
                })
            }
            Source::Measured {
                fits,
                support,
                extrapolate,
            } => Ok(measured(fits, support, r, *extrapolate)),
            Source::Truth(specimen) => Ok(Estimate {
                value: averaged(|d| specimen.eval(d), r),
                ..Estimate::default()
            }),
        }
    }

    /// The parameters' part of the uncertainty by Monte Carlo (GUM
    /// Supplement 1): `draws` parameter vectors from the normal distribution
    /// of the fit's covariance, the coefficient's standard deviation over
    /// them (measured data's: the best fit's value scaled to the anchors, as
    /// an extrapolated value is). `None` without a covariance (or one that
    /// is not positive semi-definite).
    pub fn monte_carlo_u(&self, r: &Request, draws: usize, seed: u64) -> Option<f64> {
        let (material, c, anchored) = match self {
            Source::Model {
                material,
                covariance: Some(c),
            } => (material, c, None),
            Source::Measured { fits, support, .. } => {
                let (best, material) = carrier(fits)?;
                (material, best.covariance.as_ref()?, Some(Anchored::of(support, r)))
            }
            _ => return None,
        };
        let free: Vec<usize> = (0..c.nrows()).filter(|&i| c[(i, i)] > 0.0).collect();
        let sub = DMatrix::from_fn(free.len(), free.len(), |a, b| c[(free[a], free[b])]);
        let l = sub.cholesky()?.l();
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let values: Vec<f64> = (0..draws)
            .map(|_| {
                let z = DVector::from_fn(free.len(), |_, _| StandardNormal.sample(&mut rng));
                let dp = &l * z;
                let mut m = material.clone();
                for (k, &i) in free.iter().enumerate() {
                    m.params[i] += dp[k];
                }
                anchored.as_ref().map_or_else(|| model_value(&m, r), |a| a.scaled(&m, r))
            })
            .collect();
        let mean = values.iter().sum::<f64>() / draws as f64;
        Some((values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (draws - 1) as f64).sqrt())
    }
}

impl Fitted {
    /// Whether its χ² is consistent with the data's σ ([`Adequacy`]).
    pub fn is_adequate(&self) -> bool {
        Adequacy::of(self.goodness.as_ref()) == Adequacy::Adequate
    }

    /// The model fitted, `None` for the rational function.
    pub fn material(&self) -> Option<&Material> {
        match &self.brdf {
            FittedBrdf::Model(m) => Some(m),
            FittedBrdf::Rational(_) => None,
        }
    }
}

/// The models that may carry a value beyond the data, and whether they are
/// adequate: the adequate ones; where none is (an extrapolation asked for),
/// those whose RMSE is within [`COMPARABLE_RMSE_RATIO`] of the best one's.
fn carriers(fits: &[Fitted]) -> (Vec<&Fitted>, bool) {
    let models = fits.iter().filter(|f| f.material().is_some());
    let adequate: Vec<&Fitted> = models.clone().filter(|f| f.is_adequate()).collect();
    if !adequate.is_empty() {
        return (adequate, true);
    }
    let best_rmse = models.clone().map(|f| f.rmse).fold(f64::INFINITY, f64::min);
    (models.filter(|f| f.rmse <= COMPARABLE_RMSE_RATIO * best_rmse).collect(), false)
}

/// The model that carries a value: the lowest AIC among [`carriers`].
fn carrier(fits: &[Fitted]) -> Option<(&Fitted, &Material)> {
    lowest_aic(&carriers(fits).0)
}

fn lowest_aic<'a>(fits: &[&'a Fitted]) -> Option<(&'a Fitted, &'a Material)> {
    fits.iter()
        .filter_map(|f| Some((*f, f.material()?)))
        .min_by(|a, b| a.0.aic.total_cmp(&b.0.aic))
}

/// The model fit with the lowest AIC, and its material (`None`: only the
/// rational function was fitted).
pub fn best(fits: &[Fitted]) -> Option<(&Fitted, &Material)> {
    fits.iter()
        .filter_map(|f| Some((f, f.material()?)))
        .min_by(|a, b| a.0.aic.total_cmp(&b.0.aic))
}

/// A coefficient from the data where they hold its geometry, else from the
/// best adequate model with the adequate models' spread, within the data's
/// spacing; else nothing, unless `extrapolate`.
fn measured(fits: &[Fitted], support: &Support, r: &Request, extrapolate: bool) -> Estimate {
    let mut basis = support.classify(&r.geometry.directions(), r.apertures.widest());
    if basis.provenance.on_data() {
        return Estimate {
            basis: Some(basis),
            ..carried(support, r, interpolate(&support.points, r))
        };
    }
    let models: Vec<&Fitted> = fits.iter().filter(|f| f.material().is_some()).collect();
    let refused = |basis: Basis| Estimate {
        value: f64::NAN,
        u: f64::NAN,
        basis: Some(basis),
        ..Estimate::default()
    };
    if models.is_empty() {
        // Only a rational function, which says nothing beyond its data.
        return refused(basis);
    }
    let (carriers, adequate) = carriers(fits);
    if !adequate {
        let why = no_adequate_model(&models, support.points.iter().any(|p| p.sigma > 0.0));
        if !extrapolate {
            basis.provenance = Provenance::NotMeasured;
            basis.why = format!("{}; {why}, to carry it", basis.why);
            return refused(basis);
        }
        basis.why = format!(
            "{}; {why}: extrapolated on request by the models within {COMPARABLE_RMSE_RATIO}× the best RMSE",
            basis.why
        );
    } else if basis.provenance == Provenance::NotMeasured {
        if !extrapolate {
            return refused(basis);
        }
        basis.why = format!("{}: extrapolated on request", basis.why);
    }
    basis.provenance = Provenance::Extrapolated;
    let Some((top, top_material)) = lowest_aic(&carriers) else {
        return refused(basis);
    };
    let anchored = Anchored::of(support, r);
    let (anchors, total) = (&anchored.anchors, anchored.total);
    let scaled = |m: &Material| anchored.scaled(m, r);
    let models: Vec<ModelValue> = carriers
        .iter()
        .filter_map(|f| {
            let m = f.material()?;
            Some(ModelValue {
                model: m.model.name(),
                value: scaled(m),
                rmse: f.rmse,
            })
        })
        .collect();
    let value = scaled(top_material);
    // Between two measured incidences the data themselves interpolate too
    // (linearly in the entrance angle): a way across that no model shapes.
    // Where no model is consistent with the data (carried on request), its
    // disagreement with the models' belongs in the spread; an adequate
    // model's shape between the incidences the data do not contradict.
    let between = (anchors.len() == 2 && !adequate).then(|| anchors.iter().map(|(w, _, e)| w * e.value).sum::<f64>());
    let (lo, hi) = models
        .iter()
        .map(|m| m.value)
        .chain(between)
        .fold((value, value), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let u_model = (hi - lo) / 2.0;
    // The parameters move the model's shape, not the level the anchors
    // set: propagated through the scaled value, the part they share with
    // the anchors cancels (the plate, a lobe's height), as it does in it.
    let u_params = top.covariance.as_ref().map(|c| linear_u(top_material, c, scaled));
    // The level the anchors set is known to their own relative uncertainty.
    let u_anchor = match total > 0.0 {
        true => value * anchors.iter().map(|(w, _, e)| w / total * e.u / e.value).sum::<f64>(),
        false => 0.0,
    };
    Estimate {
        value,
        u: u_params.unwrap_or(0.0).hypot(u_model).hypot(u_anchor),
        u_params,
        u_model: Some(u_model),
        basis: Some(basis),
        model: Some(top_material.model.name()),
        models,
        ..Estimate::default()
    }
}

/// Why no model may carry a value beyond the data: the best one's χ², or
/// data without uncertainties to judge any by.
fn no_adequate_model(models: &[&Fitted], sigma_given: bool) -> String {
    let best = models
        .iter()
        .filter_map(|f| Some((f.goodness?, f.material()?.model.name())))
        .max_by(|a, b| a.0.closer(&b.0));
    match best {
        Some((g, name)) => format!(
            "no model is consistent with the data within their uncertainty (the best, {name}: reduced χ² {}, p {})",
            crate::rounding::significant(g.reduced_chi2, 3),
            crate::rounding::significant(g.p_value, 2)
        ),
        None if models.iter().all(|f| f.goodness.is_none()) && sigma_given => {
            "the fit files hold no χ² (an earlier gonio wrote them): fit again to judge the models".into()
        }
        None => "the data carry no uncertainties, so no model can be shown adequate".into(),
    }
}

/// The data where they are nearest a request the data do not hold: the
/// same geometry at the measured incidences about it, each with its weight
/// and the data's value there, which scale a model's value to them.
struct Anchored {
    anchors: Vec<(f64, Request, Estimate)>,
    total: f64,
}

impl Anchored {
    fn of(support: &Support, r: &Request) -> Anchored {
        let anchors: Vec<(f64, Request, Estimate)> = anchors(support, r)
            .into_iter()
            .filter(|(_, a)| {
                support
                    .classify(&a.geometry.directions(), a.apertures.widest())
                    .provenance
                    .on_data()
            })
            .map(|(w, a)| (w, a, carried(support, &a, interpolate(&support.points, &a))))
            .filter(|(_, _, e)| e.value > 0.0)
            .collect();
        let total = anchors.iter().map(|(w, _, _)| w).sum();
        Anchored { anchors, total }
    }

    /// The model's value at `r` times its ratio to the data at the anchors.
    fn scaled(&self, m: &Material, r: &Request) -> f64 {
        let at_q = model_value(m, r);
        if self.total <= 0.0 {
            return at_q;
        }
        let ratio: f64 = self
            .anchors
            .iter()
            .map(|(w, a, e)| {
                let at_anchor = model_value(m, a);
                w / self.total * if at_anchor > 0.0 { e.value / at_anchor } else { 1.0 }
            })
            .sum();
        at_q * ratio
    }
}

/// The same geometry at the measured incidences nearest the request's
/// entrance angle, with the weights of a linear interpolation in it: the
/// two about it, or the nearest one beyond the measured range. The entrance
/// angle's components are scaled together, so the tilt keeps its direction
/// (in the coplanar geometry, β keeps its sign and the observer its side).
fn anchors(support: &Support, r: &Request) -> Vec<(f64, Request)> {
    let g = r.geometry;
    let beta = g.beta_deg().abs();
    let at = |theta: f64, w: f64| {
        let k = if beta > 0.0 { theta / beta } else { 0.0 };
        let geometry = Cie {
            beta1_deg: g.beta1_deg * k,
            beta2_deg: g.beta2_deg * k,
            ..g
        };
        (w, Request { geometry, ..*r })
    };
    match support.about(beta) {
        (Some(below), Some(above)) if above > below => {
            let w = (beta - below) / (above - below);
            vec![at(below, 1.0 - w), at(above, w)]
        }
        (Some(below), _) => vec![at(below, 1.0)],
        (None, Some(above)) => vec![at(above, 1.0)],
        (None, None) => Vec::new(),
    }
}

/// A value the data hold (the instrument's reading: on this head the BRDF
/// averaged over a point source and the detector's field, at the stages'
/// reported angles)
/// carried to the request's apertures, with what the data's own shape says
/// of its uncertainty ([`Support::local`]):
///
/// - **apertures**: to second order a disc of radius ρ reads `f + (ρ²/8)∇²f`,
///   and moving the source is, on a retro lobe, moving the view the other
///   way: so the standard reads `(ρ_s² + ρ_r² − ρ_d²)/8 · ∇²f` more than the
///   head, `∇²f` the samples' own curvature, no model's. Its uncertainty:
///   the curvature's standard error, and the neglected higher orders taken
///   as within half the correction (rectangular: `|Δ|/(2√3)`).
/// - **the arm's zero**: its error moves every sample's observation angle
///   alike. The calibration weighs it with a smooth model's slope, which on
///   a lobe of structure no model has (the glass beads' ring, whose inner
///   flank rises 2 % per 0.01°) can be a fraction of the truth; here the
///   samples' own slope along α takes its place.
///
/// Where the samples do not surround the view well enough for a quadratic,
/// neither (`u_aperture` is `None`).
fn carried(support: &Support, r: &Request, data: Estimate) -> Estimate {
    let want = r.geometry.directions();
    let Some(local) = support.local(&want) else {
        return data;
    };
    // An instrument whose apertures nobody stated: its reading is left as
    // it is, and the head's own arm does not apply.
    let Some(head) = support.instrument.apertures() else {
        return data;
    };
    let k = r.kind.factor(want.l[2], want.v[2]);
    let rho2 = |diameter_deg: f64| (diameter_deg / 2.0).powi(2);
    let reach = (rho2(r.apertures.source_deg) + rho2(r.apertures.receiver_deg) - rho2(head.source_deg) - rho2(head.receiver_deg)) / 8.0;
    let delta = reach * local.laplacian * k;
    let u_aperture = (reach.abs() * local.laplacian_se * k).hypot(delta.abs() / (2.0 * 3f64.sqrt()));
    // The arm's zero: the calibration's part of it (the nearest sample's
    // shift, zero and backlash) out, the samples' own slope in.
    let (u_data, u_arm_zero) = match support.instrument.is_this_head() {
        true => {
            let u = HeadUncertainty::default();
            let u_psi = u.zero_deg[2].hypot(u.backlash_deg[2] / 2.0);
            let model_part = data.nearest.first().map_or(0.0, |n| n.shift_psi.abs()) * k * u_psi / u.zero_deg[2];
            let data_part = local.slope_alpha.abs() * u_psi * k;
            let u_data = (data.u * data.u - model_part * model_part).max(0.0).sqrt().hypot(data_part);
            (u_data, Some(data_part))
        }
        false => (data.u, None),
    };
    Estimate {
        value: data.value + delta,
        u: u_data.hypot(u_aperture),
        u_aperture: Some(u_aperture),
        u_arm_zero,
        ..data
    }
}

/// The coefficient of a model, averaged over the apertures.
fn model_value(m: &Material, r: &Request) -> f64 {
    averaged(|d| m.eval(d), r)
}

/// The coefficient of a BRDF `f_r(directions)`, averaged over the apertures.
fn averaged(f_r: impl Fn(&Directions) -> f64, r: &Request) -> f64 {
    aperture::average(&r.geometry, r.apertures, |d| f_r(d) * r.kind.factor(d.l[2], d.v[2]))
}

/// `sqrt(gᵀ C g)`, `g` the coefficient's gradient in the parameters by
/// central differences of a small fraction of each standard error.
fn linear_u(m: &Material, c: &DMatrix<f64>, value: impl Fn(&Material) -> f64) -> f64 {
    let n = m.params.len();
    let g = DVector::from_fn(n, |i, _| {
        let sd = c[(i, i)].max(0.0).sqrt();
        if sd == 0.0 {
            return 0.0;
        }
        let h = 1e-3 * sd;
        let at = |s: f64| {
            let mut p = m.clone();
            p.params[i] += s * h;
            value(&p)
        };
        (at(1.0) - at(-1.0)) / (2.0 * h)
    });
    (g.transpose() * c * &g)[(0, 0)].max(0.0).sqrt()
}

/// Inverse-square-distance interpolation between the nearest measured
/// geometries (distance: the angles between the lights and between the
/// views, added in quadrature), at the nominal directions: measured values
/// are already averages over the head's own source and detector, so they
/// are not averaged again. Its uncertainty: the neighbours' own (taken as
/// correlated, as their calibration is) and their weighted spread about the
/// interpolated value (how much the BRDF changes between them).
fn interpolate(points: &[Point], r: &Request) -> Estimate {
    let want = folded(&r.geometry.directions());
    let mut near: Vec<(f64, &Point)> = points
        .iter()
        .map(|p| {
            let d = folded(&p.d);
            (angle_between(d.l, want.l).hypot(angle_between(d.v, want.v)), p)
        })
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    near.truncate(NEIGHBOURS);
    let weights: Vec<f64> = if near[0].0 < 1e-9 {
        near.iter().enumerate().map(|(k, _)| if k == 0 { 1.0 } else { 0.0 }).collect()
    } else {
        let w: Vec<f64> = near.iter().map(|(d, _)| 1.0 / (d * d)).collect();
        let s: f64 = w.iter().sum();
        w.iter().map(|x| x / s).collect()
    };
    let f: f64 = near.iter().zip(&weights).map(|((_, p), w)| w * p.value).sum();
    let own: f64 = near.iter().zip(&weights).map(|((_, p), w)| w * p.sigma).sum();
    let spread = near
        .iter()
        .zip(&weights)
        .map(|((_, p), w)| w * (p.value - f).powi(2))
        .sum::<f64>()
        .sqrt();
    let k = r.kind.factor(want.l[2], want.v[2]);
    Estimate {
        value: f * k,
        u: own.hypot(spread) * k,
        nearest: near
            .iter()
            .zip(&weights)
            .map(|((d, p), w)| Nearest {
                theta_i_deg: p.angles_deg[0],
                theta_o_deg: p.angles_deg[1],
                dphi_deg: p.angles_deg[2],
                distance_deg: d.to_degrees(),
                weight: *w,
                brdf_sr: p.value,
                shift_psi: p.shift_psi,
            })
            .collect(),
        ..Estimate::default()
    }
}
