//! Where a coefficient's BRDF comes from, and how its uncertainty follows:
//! a model with its parameters' covariance (linear propagation; a Monte
//! Carlo check of it), or measured data interpolated on the sphere.

use super::aperture;
use super::Request;
use crate::fit::{Dataset, Units};
use anyhow::{bail, Result};
use gonio_brdf::frame::angle_between;
use gonio_brdf::{Directions, Material};
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
    /// Measured values (`f_r`), interpolated between the nearest geometries.
    Data { points: Vec<Point> },
}

/// A measured value with its directions folded onto `Δφ ≥ 0` (isotropic).
#[derive(Debug, Clone)]
pub struct Point {
    d: Directions,
    angles_deg: [f64; 3],
    value: f64,
    sigma: f64,
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
}

/// A value, its standard uncertainty, and what the uncertainty is made of.
#[derive(Debug, Clone, Serialize)]
pub struct Estimate {
    pub value: f64,
    pub u: f64,
    /// Part of `u` from the model's parameters (linear propagation).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub u_params: Option<f64>,
    /// The measured geometries behind a value interpolated from data.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub nearest: Vec<Nearest>,
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
        let data = data.in_units(Units::Fr)?;
        if data.observations.is_empty() {
            bail!("no measured values to interpolate");
        }
        let points = data
            .observations
            .iter()
            .map(|o| {
                let d = folded(&o.directions());
                Point {
                    angles_deg: super::angles::sample_angles_deg(&d),
                    d,
                    value: o.value,
                    sigma: o.sigma.unwrap_or(0.0),
                }
            })
            .collect();
        Ok(Source::Data { points })
    }

    /// The coefficient and its standard uncertainty.
    pub fn estimate(&self, r: &Request) -> Result<Estimate> {
        match self {
            Source::Model { material, covariance } => {
                let value = model_value(material, r);
                let u_params = covariance.as_ref().map(|c| linear_u(material, c, r));
                Ok(Estimate {
                    value,
                    u: u_params.unwrap_or(0.0),
                    u_params,
                    nearest: Vec::new(),
                })
            }
            Source::Data { points } => Ok(interpolate(points, r)),
        }
    }

    /// The parameters' part of the uncertainty by Monte Carlo (GUM
    /// Supplement 1): `draws` parameter vectors from the normal distribution
    /// of the fit's covariance, the coefficient's standard deviation over
    /// them. `None` without a covariance (or one that is not positive
    /// semi-definite).
    pub fn monte_carlo_u(&self, r: &Request, draws: usize, seed: u64) -> Option<f64> {
        let Source::Model {
            material,
            covariance: Some(c),
        } = self
        else {
            return None;
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
                model_value(&m, r)
            })
            .collect();
        let mean = values.iter().sum::<f64>() / draws as f64;
        Some((values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (draws - 1) as f64).sqrt())
    }
}

/// The coefficient of a model, averaged over the apertures.
fn model_value(m: &Material, r: &Request) -> f64 {
    aperture::average(&r.geometry, r.apertures, |d| m.eval(d) * r.kind.factor(d.l[2], d.v[2]))
}

/// `sqrt(gᵀ C g)`, `g` the coefficient's gradient in the parameters by
/// central differences of a small fraction of each standard error.
fn linear_u(m: &Material, c: &DMatrix<f64>, r: &Request) -> f64 {
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
            model_value(&p, r)
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
        .map(|p| (angle_between(p.d.l, want.l).hypot(angle_between(p.d.v, want.v)), p))
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
        u_params: None,
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
            })
            .collect(),
    }
}
