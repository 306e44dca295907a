//! The retro lobe's shape by its central moments, Belcour et al. 2014 §3.D:
//! per incidence and in each [`Parametrization`], the moments up to order
//! 4 of `f_r` over the connected region about the retro direction where it
//! is at or above a threshold (which keeps the diffuse term and the mirror
//! lobe out, as the paper removed the values below a threshold), and
//! `r = (σ²max − σ²min)/σ²min` of the axis variances (Fig. 6): 0 for an
//! isotropic lobe.
//!
//! Between samples `f_r` is linear over their Delaunay triangulation in the
//! plane ([`mesh`]), integrated exactly ([`integrate`]). A file that holds
//! one side of the plane of incidence only (`Δφ ≥ 0`, as the head scans) is
//! completed by an isotropic BRDF's symmetry `f(θi, θo, −Δφ) = f(θi, θo, Δφ)`.

mod integrate;
mod mesh;
pub mod plane;
pub mod text;

use crate::fit::{data::theta_in, Dataset, Units};
use anyhow::{bail, Result};
pub use integrate::ORDER;
use mesh::{Mesh, Node};
pub use plane::Parametrization;
use serde::Serialize;
use std::str::FromStr;

/// Below it a value is not the retro lobe's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Threshold {
    /// A fraction of `f_r` in the retro direction.
    Relative(f64),
    /// `f_r` in sr⁻¹.
    Absolute(f64),
}

/// 30 % of the retro value: a cosine-power or Gaussian lobe's outline is
/// then at 1.55σ, so a lobe up to 3° wide stays within the retro rings of
/// the reference head (to 4.75°, its blind zone starting at 5°), and the
/// diffuse floor and the mirror lobe stay out of it on every material
/// tried here.
impl Default for Threshold {
    fn default() -> Self {
        Threshold::Relative(0.3)
    }
}

impl FromStr for Threshold {
    type Err = String;

    /// `rel:Q` (a fraction in (0, 1) of the retro value) or `V` (sr⁻¹, > 0).
    fn from_str(s: &str) -> Result<Self, String> {
        let number = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("`{t}` is not a number"));
        match s.strip_prefix("rel:") {
            Some(q) => match number(q)? {
                q if q > 0.0 && q < 1.0 => Ok(Threshold::Relative(q)),
                q => Err(format!(
                    "a relative threshold is a fraction of the retro value between 0 and 1, not {q}"
                )),
            },
            None => match number(s)? {
                v if v > 0.0 && v.is_finite() => Ok(Threshold::Absolute(v)),
                v => Err(format!("an absolute threshold is a positive f_r in sr⁻¹, not {v}")),
            },
        }
    }
}

impl Threshold {
    fn at(self, retro: f64) -> f64 {
        match self {
            Threshold::Relative(q) => q * retro,
            Threshold::Absolute(v) => v,
        }
    }
}

/// The lobe at one incidence in one plane. Angles in degrees; `central` is
/// `μ_{i,j}` in deg^(i+j) for `2 ≤ i + j ≤ 4`, as `[i, j, value]`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Moments {
    /// `f_r` interpolated in the retro direction, sr⁻¹.
    pub retro_sr: f64,
    pub threshold_sr: f64,
    /// Samples at or above the threshold in the lobe.
    pub samples: usize,
    /// The lobe reaches the edge of the measured directions above the
    /// threshold: its moments are those of a truncated lobe.
    pub truncated: bool,
    /// The widest stretch between samples the lobe is interpolated across
    /// (a triangle edge with an end at or above the threshold), in lobe
    /// widths along it: `√(eᵀ Σ⁻¹ e)` with `Σ` the lobe's covariance, the
    /// same in either plane for the same samples.
    pub gap_sigma: f64,
    /// `gap_sigma > 1`: samples lie more than a lobe width apart somewhere
    /// in it, its outline there is the interpolation's rather than the
    /// data's, and `r` follows the sampling more than the material (a lobe
    /// reaching the head's blind zone, 5°–11.5° from the laser, does this:
    /// a higher threshold keeps it inside the retro rings).
    pub under_sampled: bool,
    /// `∫ f_r dx dy`, sr⁻¹·deg².
    pub norm: f64,
    pub mean_deg: [f64; 2],
    pub central: Vec<(usize, usize, f64)>,
    pub sigma_deg: [f64; 2],
    /// `(σ²max − σ²min)/σ²min`.
    pub r: f64,
    /// `μ11 / (σx σy)`.
    pub correlation: f64,
    /// `μ40/σx⁴`, `μ04/σy⁴`: 3 for a normal distribution.
    pub kurtosis: [f64; 2],
}

/// One incidence in one plane: its moments, or why there are none.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Entry {
    pub theta_i_deg: f64,
    pub parametrization: Parametrization,
    /// Samples at this incidence (before the symmetry completion).
    pub samples: usize,
    /// Whether `Δφ → −Δφ` completed the plane.
    pub mirrored: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moments: Option<Moments>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub missing: Option<String>,
}

/// Every incidence of `data` in both planes, in order of incidence.
pub fn analyse(data: &Dataset, threshold: Threshold) -> Result<Vec<Entry>> {
    let data = data.filter(|o| o.theta_o.cos() > 1e-6).in_units(Units::Fr)?;
    let mut out = Vec::new();
    for ti in data.incidence_angles_deg() {
        let at: Vec<_> = data
            .observations
            .iter()
            .filter(|o| theta_in(o.theta_i, &[ti]) && o.value.is_finite())
            .collect();
        let mirrored = !at.iter().any(|o| o.dphi.sin() < -1e-9);
        for parametrization in Parametrization::BOTH {
            let nodes = at.iter().flat_map(|o| {
                let node = |dphi: f64| Node {
                    p: parametrization.coordinates(&gonio_brdf::Directions::from_angles(o.theta_i, o.theta_o, dphi)),
                    f: o.value,
                };
                let twin = (mirrored && o.dphi.sin() > 1e-9).then(|| node(-o.dphi));
                std::iter::once(node(o.dphi)).chain(twin)
            });
            let (moments, missing) = match lobe(nodes, threshold) {
                Ok(m) => (Some(m), None),
                Err(e) => (None, Some(format!("{e:#}"))),
            };
            out.push(Entry {
                theta_i_deg: ti,
                parametrization,
                samples: at.len(),
                mirrored,
                moments,
                missing,
            });
        }
    }
    if out.iter().all(|e| e.moments.is_none()) {
        match out.first() {
            None => bail!("no sample to analyse"),
            Some(e) => bail!(
                "no retro lobe found at any incidence (at θi = {}°: {})",
                e.theta_i_deg,
                e.missing.as_deref().unwrap_or_default()
            ),
        }
    }
    Ok(out)
}

fn lobe(nodes: impl Iterator<Item = Node>, threshold: Threshold) -> Result<Moments> {
    let mesh = Mesh::new(nodes)?;
    let Some((seed, retro_sr)) = mesh.at([0.0, 0.0]) else {
        bail!("the retro direction lies outside the measured directions");
    };
    let threshold_sr = threshold.at(retro_sr);
    if !(retro_sr >= threshold_sr && retro_sr > 0.0) {
        bail!("f_r in the retro direction, {retro_sr:.3e} sr⁻¹, is below the threshold {threshold_sr:.3e} sr⁻¹: no retro lobe");
    }
    let region = mesh.lobe(seed, threshold_sr);
    if region.samples < 3 {
        bail!("{} sample(s) at or above the threshold: too few for a lobe's shape", region.samples);
    }
    let Some(m) = integrate::moments(&region.pieces) else {
        bail!("the lobe has no area above the threshold");
    };
    let (vx, vy, cxy) = (m.central[2][0], m.central[0][2], m.central[1][1]);
    let det = vx * vy - cxy * cxy;
    let gap_sigma = region
        .edges
        .iter()
        .map(|[x, y]| ((vy * x * x - 2.0 * cxy * x * y + vx * y * y) / det).sqrt())
        .fold(0.0, f64::max);
    let central = (2..=ORDER)
        .flat_map(|n| (0..=n).rev().map(move |i| (i, n - i)))
        .map(|(i, j)| (i, j, m.central[i][j]))
        .collect();
    Ok(Moments {
        retro_sr,
        threshold_sr,
        samples: region.samples,
        truncated: region.truncated,
        gap_sigma,
        under_sampled: gap_sigma > 1.0,
        norm: m.norm,
        mean_deg: m.mean,
        central,
        sigma_deg: [vx.sqrt(), vy.sqrt()],
        r: (vx.max(vy) - vx.min(vy)) / vx.min(vy),
        correlation: cxy / (vx * vy).sqrt(),
        kurtosis: [m.central[4][0] / (vx * vx), m.central[0][4] / (vy * vy)],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::data::Observation;
    use gonio_brdf::{Directions, GeometryTerms};

    /// `f` on θo 0°–89° and Δφ 0°–180° by 1° (one side, as the head scans)
    /// at the paper's three incidences.
    fn data(f: impl Fn(&Directions) -> f64) -> Dataset {
        let mut observations = Vec::new();
        for ti in [15.0f64, 30.0, 60.0] {
            for to in 0..90 {
                for dp in 0..=180 {
                    let (theta_i, theta_o, dphi) = (ti.to_radians(), (to as f64).to_radians(), (dp as f64).to_radians());
                    let value = f(&Directions::from_angles(theta_i, theta_o, dphi));
                    observations.push(Observation {
                        theta_i,
                        theta_o,
                        dphi,
                        value,
                        sigma: None,
                        shared: Default::default(),
                    });
                }
            }
        }
        Dataset::new(Units::Fr, observations)
    }

    fn r_of(entries: &[Entry], p: Parametrization) -> Vec<f64> {
        entries
            .iter()
            .filter(|e| e.parametrization == p)
            .map(|e| e.moments.as_ref().unwrap().r)
            .collect()
    }

    #[test]
    fn a_lobe_of_the_back_cosine_is_isotropic_in_the_back_plane_only() {
        // A diffuse floor, a mirror lobe and a retro lobe in cos_B: the
        // threshold keeps the floor and the mirror lobe out.
        let entries = analyse(
            &data(|d| {
                let g = GeometryTerms::new(d);
                0.1 + 2.0 * g.mirror.max(0.0).powi(400) + 5.0 * g.cos_b.powi(150)
            }),
            Threshold::default(),
        )
        .unwrap();
        let back = r_of(&entries, Parametrization::Back);
        assert!(back.iter().all(|&r| r < 0.05), "{back:?}");
        let view = r_of(&entries, Parametrization::LightView);
        assert!(view[2] > 0.5, "at θi = 60° the back lobe is anisotropic about the light: {view:?}");
        for e in &entries {
            let m = e.moments.as_ref().unwrap();
            assert!(e.mirrored && !m.truncated && !m.under_sampled && m.samples > 30, "{e:?}");
            assert!(m.correlation.abs() < 1e-6 && m.mean_deg[1].abs() < 1e-9, "{e:?}");
        }
    }

    #[test]
    fn a_lobe_of_the_view_cosine_is_isotropic_about_the_light() {
        let entries = analyse(
            &data(|d| 0.05 + 4.0 * GeometryTerms::new(d).lv.max(0.0).powi(150)),
            Threshold::default(),
        )
        .unwrap();
        let view = r_of(&entries, Parametrization::LightView);
        assert!(view.iter().all(|&r| r < 0.05), "{view:?}");
        // cos^n ≈ a round Gaussian cut where it falls to t: with s = ρ²/2σ²
        // weighted by e^(−s) on [0, ln(1/t)], a marginal's kurtosis is
        // (3/8)E[ρ⁴] / ((1/2)E[ρ²])² = 1.5 E[s²]/E[s]², 2.22 at t = 0.3.
        let l = (1.0f64 / 0.3).ln();
        let (m1, m2) = (1.0 - (-l).exp() * (1.0 + l), 2.0 - (-l).exp() * (l * l + 2.0 * l + 2.0));
        let want = 1.5 * m2 * (1.0 - (-l).exp()) / (m1 * m1);
        for e in entries.iter().filter(|e| e.parametrization == Parametrization::LightView) {
            let m = e.moments.as_ref().unwrap();
            assert!(m.kurtosis.iter().all(|&k| (k - want).abs() < 0.03), "{m:?} against {want}");
            assert!(m.mean_deg[0].abs() < 0.2, "{m:?}");
        }
    }

    #[test]
    fn an_elongated_lobe_is_anisotropic_in_both() {
        // Gaussian in the back plane, σx = 2σy: r = 3 there, and far from 0
        // in the other. Narrow enough that its 10 % contour stays inside the
        // back plane's reach at θi = 60° (15° towards the horizon).
        let entries = analyse(
            &data(|d| {
                let [x, y] = Parametrization::Back.coordinates(d);
                0.1 + 6.0 * (-(x / 6.0).powi(2) / 2.0 - (y / 3.0).powi(2) / 2.0).exp()
            }),
            Threshold::default(),
        )
        .unwrap();
        let back = r_of(&entries, Parametrization::Back);
        assert!(back.iter().all(|&r| (r - 3.0).abs() < 0.15), "{back:?}");
        assert!(entries.iter().all(|e| !e.moments.as_ref().unwrap().truncated));
        assert!(r_of(&entries, Parametrization::LightView).iter().all(|&r| r > 0.5));
    }

    #[test]
    fn a_lobe_cut_by_the_blind_zone_is_said_to_be_under_sampled() {
        // σ = 2.3° about the light, its 10 % outline at 5°: the samples
        // 5°–11.5° from the laser removed, as the head cannot take them.
        let lobe = |d: &Directions| 0.05 + 4.0 * GeometryTerms::new(d).lv.max(0.0).powi(600);
        let mut blind = data(lobe);
        blind.observations.retain(|o| {
            let d = Directions::from_angles(o.theta_i, o.theta_o, o.dphi);
            !(5.0..11.5).contains(&gonio_brdf::frame::angle_between(d.l, d.v).to_degrees())
        });
        for (set, cut) in [(data(lobe), false), (blind, true)] {
            for e in analyse(&set, Threshold::Relative(0.1)).unwrap() {
                let m = e.moments.as_ref().unwrap();
                assert_eq!(m.under_sampled, cut, "{e:?}");
                assert!(cut == (m.gap_sigma > 2.0), "{e:?}");
            }
        }
    }

    #[test]
    fn no_lobe_is_said_and_thresholds_are_read() {
        let flat = data(|_| 0.1);
        let e = analyse(&flat, Threshold::Absolute(1.0)).unwrap_err();
        assert!(format!("{e:#}").contains("below the threshold"), "{e:#}");
        assert_eq!("rel:0.2".parse(), Ok(Threshold::Relative(0.2)));
        assert_eq!("3".parse(), Ok(Threshold::Absolute(3.0)));
        for bad in ["rel:1.5", "-1", "rel:x", "nan"] {
            assert!(bad.parse::<Threshold>().is_err(), "{bad}");
        }
    }
}
