//! A BRDF as an RGL `.bsdf` file (Dupuy & Jakob 2018, "An adaptive
//! parameterization for efficient material acquisition and rendering"): the
//! tensor file that Mitsuba 3's `measured` plugin and pbrt-v4's
//! `MeasuredBxDF` load, so that a measured material can be rendered.
//!
//! What a renderer does with the file (`src/bsdfs/measured.cpp`), for a
//! viewer direction `ωi` and a light direction `ωo` (both in the upper
//! hemisphere; Mitsuba's `si.wi` is the camera's side):
//! 1. `m = (ωi + ωo)/‖ωi + ωo‖`, mapped to the unit square by
//!    `u = (√(θm / (π/2)), (φm − φi + π)/2π)` (isotropic files);
//! 2. `s = vndf⁻¹(u)` through the continuous marginal warp of the `vndf`
//!    table at the viewer's `(φi, θi)` ([`marginal`]);
//! 3. `f·cos θo = spectra(s) · ndf(u) / (4 σ(ωi))` (`jacobian = 1`; pbrt
//!    always applies this factor, so the file sets it).
//!
//! The file is built as the paper builds it: `ndf` and `sigma` from the
//! retroreflection ([`microfacet`]), the warp from the visible normals
//! `⟨ωi·m⟩ D(m) / σ(ωi)`, the spectra on the warped grid and the luminance
//! warp from them. One departure, because a retroreflector is not a
//! microfacet surface: its lobe sits at `m = ωi`, where the visible-normal
//! density has nothing special, so a share of each slice's warp
//! ([`Options::retro_share`]) is a bump about `m = ωi`. The warp is only a
//! change of variables (both renderers compute densities from the table
//! itself), so this moves grid points into the retro lobe without changing
//! what is evaluated. Half of each warp ([`Options::curvature_share`])
//! follows the tabulated function itself, where it curves, so that a
//! narrow lobe's skirt does not fall between two columns whatever lobe it
//! is. From 3° of incidence on, the retro point then sits
//! at the same node of the warped square at every incidence, so
//! interpolating between incidences keeps the peak.
//!
//! The table's incidence is the viewer's: a render sees the material as the
//! head sees it, with the light where the head's laser is (`models.md`'s
//! `f(l, v)` with `l = ωo`, `v = ωi`).

pub mod marginal;
pub mod microfacet;
pub mod tensor;

use anyhow::{bail, ensure, Result};
use gonio_brdf::frame::{cross, dot, normalize};
use gonio_brdf::Directions;
use marginal::{Grid, Marginal};
use microfacet::Microfacet;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};
use tensor::Field;

/// The laser's wavelength (nm): what the head measures at.
pub const LASER_NM: f32 = 633.0;
/// The visible range the values are copied over with [`Spectrum::Visible`] (nm).
const VISIBLE_NM: [f32; 2] = [360.0, 830.0];
/// Largest incidence tabulated (degrees); beyond it a renderer holds the last slice.
const THETA_I_MAX_DEG: f64 = 88.0;
/// Share of each warp's azimuths spread evenly, for lobes away from the
/// plane of incidence (the mirror lobe at grazing incidence).
const AZIMUTH_FLAT_SHARE: f64 = 0.2;
/// Widest the bump about the mirror's half vector grows at grazing incidence (degrees).
const MIRROR_WIDTH_MAX_DEG: f64 = 15.0;
/// Incidences up to which the slices are four times as close (degrees):
/// there the mirror lobe leaves the retro one (at twice the incidence) and
/// the retro direction's node moves to the middle of the warped square (by
/// `2 × bump width`, 3° by default).
pub const FINE_DEG: f64 = 4.0;
/// Bounds on the options, which keep a file under about 1.5 GB.
const MIN_STEP_DEG: f64 = 0.05;
const MAX_SIDE: usize = 513;
/// Floor of the NDF relative to its largest value, so that `spectra = f·cos·4σ/D`
/// stays finite at grazing half vectors where `D → 0`.
const NDF_FLOOR: f64 = 1e-3;

/// Which wavelengths the values are given at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Spectrum {
    /// At the laser's 633 nm only, which a spectral renderer holds for every wavelength.
    Laser,
    /// The same values at 360 and 830 nm: a grey material over the visible, by assumption.
    Visible,
    /// The same values in red, green and blue (an `rgb` table, no
    /// wavelengths): for a renderer's RGB variants, grey by assumption.
    Rgb,
}

/// Sizes of the tables and the share of the warp given to the retro lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Step between incidence slices over `[0°, 88°]` (degrees); a quarter
    /// of it up to [`FINE_DEG`], where the retro and mirror lobes part and
    /// the retro direction moves across the warped square.
    pub theta_i_step_deg: f64,
    /// Side of the warped square's grid (`spectra` or `rgb`, `luminance`).
    pub spectra: usize,
    /// Side of the `vndf` grid over the half-vector square.
    pub vndf: usize,
    /// Side of the `ndf` and `sigma` grids.
    pub ndf: usize,
    /// Shares of each warp in the bumps about the retro and the mirror
    /// direction; the rest follows the visible normals.
    pub retro_share: f64,
    pub mirror_share: f64,
    /// Angular radius (standard deviation, degrees) of the bumps, in the half vector.
    pub bump_width_deg: f64,
    /// Share of each warp placed where the tabulated function curves,
    /// whatever its lobes (`curvature_axes`); the bumps and the visible
    /// normals share the rest.
    pub curvature_share: f64,
    pub spectrum: Spectrum,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            theta_i_step_deg: 0.5,
            spectra: 97,
            vndf: 97,
            ndf: 64,
            retro_share: 0.4,
            mirror_share: 0.2,
            bump_width_deg: 1.5,
            curvature_share: 0.5,
            spectrum: Spectrum::Laser,
        }
    }
}

/// A tabulated BRDF: the file's fields and the renderer's view of them.
#[derive(Debug, Clone)]
pub struct Table {
    pub fields: Vec<Field>,
    theta_i: Vec<f64>,
    ndf: Grid,
    sigma: Grid,
    vndf: Marginal,
    spectra: Grid,
}

/// The incidences tabulated (radians): steps of `step / 4` up to
/// [`FINE_DEG`], then `step`. A last step shorter than a quarter of the
/// others is merged into the one before it, so that the values stay
/// distinct once stored as `f32`.
fn incidences(step_deg: f64) -> Vec<f64> {
    let mut out = vec![0.0];
    let mut t: f64 = 0.0;
    while t < THETA_I_MAX_DEG - 1e-9 {
        t = (t + if t < FINE_DEG { step_deg / 4.0 } else { step_deg }).min(THETA_I_MAX_DEG);
        out.push(t);
    }
    let n = out.len();
    if n > 2 && out[n - 1] - out[n - 2] < step_deg / 4.0 {
        out.remove(n - 2);
    }
    out.into_iter().map(f64::to_radians).collect()
}

fn theta2u(theta: f64) -> f64 {
    (theta / FRAC_PI_2).max(0.0).sqrt()
}

fn u2theta(u: f64) -> f64 {
    u * u * FRAC_PI_2
}

fn phi2u(phi: f64) -> f64 {
    (phi + PI) / (2.0 * PI)
}

fn u2phi(u: f64) -> f64 {
    (2.0 * u - 1.0) * PI
}

fn unit(theta: f64, phi: f64) -> [f64; 3] {
    [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
}

/// Polar angle, accurate near the normal (the plugin's `elevation`).
fn elevation(d: [f64; 3]) -> f64 {
    let dist = (d[0] * d[0] + d[1] * d[1] + (d[2] - 1.0).powi(2)).sqrt();
    2.0 * (0.5 * dist).min(1.0).asin()
}

/// `d(solid angle of m) / d(u)`: `2π² u sin θm`, floored as the plugin floors it.
fn solid_angle_per_u(u: f64) -> f64 {
    (2.0 * PI * PI * u * u2theta(u).sin()).max(1e-6)
}

/// A BRDF to tabulate: sr⁻¹ at a geometry, callable from the threads
/// that tabulate the incidences side by side.
pub type Brdf<'a> = dyn Fn(&Directions) -> f64 + Sync + 'a;

/// `f·cos θo` with the light at `wo` and the viewer at `wi` (the table's
/// incidence): what the `measured` plugin's `eval` returns for them.
pub fn fr_cos(brdf: &Brdf, wi: [f64; 3], wo: [f64; 3]) -> f64 {
    let d = Directions::in_frame([0.0, 0.0, 1.0], wo, wi, [1.0, 0.0, 0.0]);
    brdf(&d) * wo[2]
}

/// The node grid of a `w × w` square, row-major with `x` fastest.
fn nodes(w: usize) -> impl Iterator<Item = [f64; 2]> {
    let step = 1.0 / (w - 1) as f64;
    (0..w * w).map(move |k| [(k % w) as f64 * step, (k / w) as f64 * step])
}

impl Table {
    /// Tabulates `brdf` (sr⁻¹, isotropic, in `models.md`'s frame). A value
    /// that is NaN, infinite or negative is an error naming its geometry.
    pub fn new(brdf: &Brdf, description: &str, opt: &Options) -> Result<Table> {
        ensure!(
            opt.theta_i_step_deg >= MIN_STEP_DEG && opt.theta_i_step_deg <= 45.0,
            "the incidence step must be in [{MIN_STEP_DEG}°, 45°]"
        );
        let sides = [opt.spectra, opt.vndf, opt.ndf];
        ensure!(
            sides.iter().all(|s| (2..=MAX_SIDE).contains(s)),
            "every grid side must be in [2, {MAX_SIDE}]"
        );
        ensure!(
            opt.retro_share >= 0.0 && opt.mirror_share >= 0.0 && opt.retro_share + opt.mirror_share < 1.0,
            "the retro and mirror shares must be ≥ 0 and leave some of the warp to the visible normals"
        );
        ensure!(opt.bump_width_deg > 0.0, "the bumps' width must be positive");
        ensure!(
            (0.0..=1.0).contains(&opt.curvature_share),
            "the curvature's share must be in [0, 1]"
        );
        let theta_i = incidences(opt.theta_i_step_deg);
        let mut bad = None;
        let micro = Microfacet::from_retro(|t| {
            let w = unit(t, 0.0);
            let f = brdf(&Directions { l: w, v: w });
            if !(f.is_finite() && f >= 0.0) && bad.is_none() {
                bad = Some((t.to_degrees(), f));
            }
            f.max(0.0)
        });
        if let Some((t, f)) = bad {
            bail!("cannot tabulate: f = {f} at the retro direction θ = {t:.1}°");
        }
        let (n, v, s) = (opt.ndf, opt.vndf, opt.spectra);
        let d_max = (0..n).map(|k| micro.ndf(u2theta(k as f64 / (n - 1) as f64))).fold(0.0, f64::max);
        ensure!(
            d_max > 0.0 && d_max.is_finite(),
            "cannot tabulate: no retroreflection at any incidence to build the NDF from"
        );
        let ndf = Grid {
            w: n,
            h: n,
            params: vec![0.0],
            values: nodes(n).map(|[x, _]| micro.ndf(u2theta(x)).max(NDF_FLOOR * d_max) as f32).collect(),
        };
        let sigma = Grid {
            w: n,
            h: n,
            params: vec![0.0],
            values: nodes(n).map(|[x, _]| micro.sigma(u2theta(x)) as f32).collect(),
        };

        // The incidences are independent: tabulated side by side.
        let vndf_values: Vec<f32> = theta_i
            .par_iter()
            .map(|&ti| warp_slice(brdf, &micro, &ndf, ti, v, opt))
            .collect::<Vec<_>>()
            .concat();
        let vndf = Marginal::new(&vndf_values, v, v, &theta_i);
        let slices = theta_i
            .par_iter()
            .map(|&ti| spectra_slice(brdf, &ndf, &sigma, &vndf, ti, s))
            .collect::<Result<Vec<_>>>()?;
        let (spectra_values, luminance): (Vec<f32>, Vec<f32>) =
            slices.into_iter().flat_map(|(values, lum)| values.into_iter().zip(lum)).unzip();
        let spectra = Grid {
            w: s,
            h: s,
            params: theta_i.clone(),
            values: spectra_values,
        };
        let fields = fields(description, &theta_i, &ndf, &sigma, &vndf_values, &luminance, &spectra, opt);
        Ok(Table {
            fields,
            theta_i,
            ndf,
            sigma,
            vndf,
            spectra,
        })
    }

    /// `f·cos θo` as the `measured` plugin evaluates the file, for the viewer
    /// at `wi` and the light at `wo` (unit vectors, upper hemisphere).
    pub fn eval(&self, wi: [f64; 3], wo: [f64; 3]) -> f64 {
        if wi[2] <= 0.0 || wo[2] <= 0.0 {
            return 0.0;
        }
        let m = normalize([wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]]);
        let (theta_i, phi_i) = (elevation(wi), wi[1].atan2(wi[0]));
        let (theta_m, phi_m) = (elevation(m), m[1].atan2(m[0]));
        let u_wi = [theta2u(theta_i), phi2u(phi_i)];
        let mut u_m = [theta2u(theta_m), phi2u(phi_m - phi_i)];
        u_m[1] -= u_m[1].floor();
        let (sample, _) = self.vndf.invert(u_m, theta_i);
        self.spectra.eval(sample, theta_i) * self.ndf.eval(u_m, 0.0) / (4.0 * self.sigma.eval(u_wi, 0.0))
    }

    /// The incidences tabulated (radians).
    pub fn theta_i(&self) -> &[f64] {
        &self.theta_i
    }

    /// The file's bytes.
    pub fn bytes(&self) -> Vec<u8> {
        tensor::encode(&self.fields)
    }
}

/// One incidence's warp density over the half-vector square (`x` = θm, `y`
/// = φm − φi), as a product `g(x)·h(y)`: a share
/// [`Options::curvature_share`] placed where the function curves
/// ([`curvature_axes`]), the rest in [`bump_axes`]; then centred on the
/// retro direction ([`centred`]). A product keeps every row's conditional
/// the same, so that neighbouring rows of the warped grid stand for the
/// same polar angles and interpolating between them does not mix the
/// inside of a lobe with its outside.
fn warp_slice(brdf: &Brdf, micro: &Microfacet, ndf: &Grid, theta_i: f64, v: usize, opt: &Options) -> Vec<f32> {
    let (gb, hb) = bump_axes(micro, theta_i, v, opt);
    let (gc, hc) = curvature_axes(brdf, ndf, theta_i, v);
    let share = opt.curvature_share;
    let g = mix(&[(&gb, 1.0 - share), (&gc, share)]);
    let h = mix(&[(&hb, 1.0 - share), (&hc, share)]);
    let target = 0.5 * (theta_i / (2.0 * opt.bump_width_deg.to_radians())).min(1.0);
    let g = centred(&g, theta2u(theta_i), target);
    h.iter().flat_map(|&hy| g.iter().map(move |&gx| (gx * hy) as f32)).collect()
}

/// One incidence's stored values, `f·cos θo · 4σ / D` at the nodes of its
/// warped square, and its luminance warp's.
fn spectra_slice(brdf: &Brdf, ndf: &Grid, sigma: &Grid, vndf: &Marginal, ti: f64, s: usize) -> Result<(Vec<f32>, Vec<f32>)> {
    let wi = unit(ti, 0.0);
    let scale = 4.0 * sigma.eval([theta2u(ti), phi2u(0.0)], 0.0);
    let mut values = Vec::with_capacity(s * s);
    let mut lum_slice = Vec::with_capacity(s * s);
    for node in nodes(s) {
        let (u, pdf) = vndf.sample(node, ti);
        let m = unit(u2theta(u[0]), u2phi(u[1]));
        let cos_im = dot(wi, m);
        let wo = [
            2.0 * cos_im * m[0] - wi[0],
            2.0 * cos_im * m[1] - wi[1],
            2.0 * cos_im * m[2] - wi[2],
        ];
        // Below the horizon no light arrives: f·cos θo = 0 there.
        let f_cos = if wo[2] > 0.0 { fr_cos(brdf, wi, wo) } else { 0.0 };
        if !(f_cos.is_finite() && f_cos >= 0.0) {
            let (tl, to, dphi) = Directions::in_frame([0.0, 0.0, 1.0], wo, wi, [1.0, 0.0, 0.0]).angles();
            bail!(
                "cannot tabulate: f = {} at θi = {:.2}°, θo = {:.2}°, Δφ = {:.2}°",
                f_cos / wo[2],
                tl.to_degrees(),
                to.to_degrees(),
                dphi.to_degrees()
            );
        }
        let d = ndf.eval(u, 0.0);
        let value = f_cos * scale / d;
        ensure!(
            value.is_finite(),
            "cannot tabulate: a stored value is {value} (σ = {}, D = {d})",
            scale / 4.0
        );
        values.push(value as f32);
        // The luminance warp: f·cos θo over the warp's own density
        // of ωo, so that sampling it draws ωo in proportion to f·cos θo.
        let pdf_wo = pdf / (solid_angle_per_u(u[0]) * 4.0 * cos_im.max(1e-6));
        lum_slice.push(if cos_im > 0.0 { f_cos / pdf_wo } else { 0.0 });
    }
    let mean = lum_slice.iter().sum::<f64>() / lum_slice.len() as f64;
    let luminance = lum_slice.iter().map(|&l| (l + 1e-3 * mean.max(1e-30)) as f32).collect();
    Ok((values, luminance))
}

/// The fixed part of a warp, per axis: the marginals of the visible
/// normals `⟨ωi·m⟩ D(m)/σ(ωi)`, mixed in `g` with bumps about the retro
/// (`θm = θi`) and the mirror (`θm = 0`) half vectors and in `h` with one
/// about the retro azimuth (`φm = φi`) and an even share.
fn bump_axes(micro: &Microfacet, theta_i: f64, v: usize, opt: &Options) -> (Vec<f64>, Vec<f64>) {
    let wi = unit(theta_i, 0.0);
    let width = opt.bump_width_deg.to_radians();
    let bump = |d: f64, w: f64| (-(d / w).powi(2) / 2.0).exp();
    let axis: Vec<f64> = (0..v).map(|k| k as f64 / (v - 1) as f64).collect();
    let (mut g_vis, mut h_vis) = (vec![0.0; v], vec![0.0; v]);
    for (k, [x, y]) in nodes(v).enumerate() {
        let (tm, pm) = (u2theta(x), u2phi(y));
        let p = micro.ndf(tm) * dot(wi, unit(tm, pm)).max(0.0) * 2.0 * PI * PI * x * tm.sin();
        g_vis[k % v] += p;
        h_vis[k / v] += p;
    }
    // d θm / d u_x = π u: the bumps are densities in θm and φm, taken to u.
    let g_retro: Vec<f64> = axis.iter().map(|&x| bump(u2theta(x) - theta_i, width) * PI * x).collect();
    // A tilt of m across the plane of incidence turns ωo by only about
    // 2 cos θi times as much: the mirror lobe is wider in m by 1/cos θi.
    let mirror_width = (width / theta_i.cos().max(1e-9)).min(MIRROR_WIDTH_MAX_DEG.to_radians());
    let g_mirror: Vec<f64> = axis.iter().map(|&x| bump(u2theta(x), mirror_width) * PI * x).collect();
    let phi_width = (width / theta_i.sin().max(1e-9)).min(PI);
    let h_retro: Vec<f64> = axis.iter().map(|&y| bump(u2phi(y), phi_width)).collect();
    let g = mix(&[
        (&g_vis, 1.0 - opt.retro_share - opt.mirror_share),
        (&g_retro, opt.retro_share),
        (&g_mirror, opt.mirror_share),
    ]);
    let h = mix(&[
        (&h_vis, 1.0 - opt.retro_share - AZIMUTH_FLAT_SHARE),
        (&h_retro, opt.retro_share),
        (&vec![1.0; v], AZIMUTH_FLAT_SHARE),
    ]);
    (g, h)
}

/// Share of [`curvature_axes`]' density spread evenly over the square.
const CURVATURE_FLOOR: f64 = 0.15;

/// One incidence's warp density along each axis from what the renderer
/// interpolates, `F = f·cos θo / D(m)` over the half-vector square: a node
/// spacing that evens out the relative error of linear interpolation,
/// `Δ ∝ (|F''|/F)^-½` along each axis (the largest over the other axis, so
/// that one product `g(x)·h(y)` serves every row), with a share
/// [`CURVATURE_FLOOR`] spread evenly. Views within 3° of the horizon,
/// where `f·cos θo` bends to zero, take none.
fn curvature_axes(brdf: &Brdf, ndf: &Grid, theta_i: f64, v: usize) -> (Vec<f64>, Vec<f64>) {
    // The function is sampled four times as finely as the warp's nodes.
    let fine = 4 * (v - 1) + 1;
    let wi = unit(theta_i, 0.0);
    let step = 1.0 / (fine - 1) as f64;
    let d: Vec<f64> = (0..fine).map(|i| ndf.eval([i as f64 * step, 0.0], 0.0)).collect();
    let mut f = vec![0.0; fine * fine];
    let mut lit = vec![false; fine * fine];
    let horizon = 3f64.to_radians().sin();
    for j in 0..fine {
        for i in 0..fine {
            let m = unit(u2theta(i as f64 * step), u2phi(j as f64 * step));
            let c = dot(wi, m);
            let wo = [2.0 * c * m[0] - wi[0], 2.0 * c * m[1] - wi[1], 2.0 * c * m[2] - wi[2]];
            if wo[2] > 0.0 {
                f[j * fine + i] = fr_cos(brdf, wi, wo).max(0.0) / d[i];
                lit[j * fine + i] = wo[2] > horizon;
            }
        }
    }
    let mean = f.iter().sum::<f64>() / f.len() as f64;
    let floor = 1e-3 * mean.max(1e-300);
    let (mut g, mut h) = (vec![0.0f64; fine], vec![0.0f64; fine]);
    for (j, hj) in h.iter_mut().enumerate().take(fine - 1).skip(1) {
        for (i, gi) in g.iter_mut().enumerate().take(fine - 1).skip(1) {
            let k = j * fine + i;
            if !lit[k] {
                continue;
            }
            let fk = f[k] + floor;
            let ex = ((f[k + 1] - 2.0 * f[k] + f[k - 1]).abs() / fk).sqrt();
            let ey = ((f[k + fine] - 2.0 * f[k] + f[k - fine]).abs() / fk).sqrt();
            *gi = gi.max(ex);
            *hj = hj.max(ey);
        }
    }
    let pool = |a: &[f64]| -> Vec<f64> {
        let at = |n: usize| n * (fine - 1) / (v - 1);
        let cells: Vec<f64> = (0..v - 1)
            .map(|n| a[at(n)..=at(n + 1)].iter().copied().fold(0.0, f64::max))
            .collect();
        let nodes: Vec<f64> = (0..v).map(|n| cells[n.saturating_sub(1)].max(cells[n.min(v - 2)])).collect();
        let mean = nodes.iter().sum::<f64>() / v as f64;
        nodes
            .iter()
            .map(|x| {
                if mean > 0.0 {
                    (1.0 - CURVATURE_FLOOR) * x / mean + CURVATURE_FLOOR
                } else {
                    1.0
                }
            })
            .collect()
    };
    (pool(&g), pool(&h))
}

/// `g` with an even density added on the side of `u*` that holds less
/// than `target` of it, so that a share `target` of the whole lies below
/// `u*`. With `target = ½` (from a few degrees of incidence on) the retro
/// direction maps to the middle column of the warped square at every
/// incidence, a node when its side is odd: the retro value is read off a
/// node, not interpolated across a narrow peak or dip, at the slices and
/// between them. The lobes themselves keep their share of the columns.
fn centred(g: &[f64], u_star: f64, target: f64) -> Vec<f64> {
    let n = g.len();
    let x = |k: usize| k as f64 / (n - 1) as f64;
    let low = cdf(g, u_star) < target * cdf(g, 1.0);
    let even: Vec<f64> = (0..n).map(|k| if (x(k) < u_star) == low { 1.0 } else { 0.0 }).collect();
    // cdf(g + a·even, u*) = target · cdf(g + a·even, 1)
    let a = (cdf(g, u_star) - target * cdf(g, 1.0)) / (target * cdf(&even, 1.0) - cdf(&even, u_star));
    if !(a >= 0.0 && a.is_finite()) {
        return g.to_vec();
    }
    (0..n).map(|k| g[k] + a * even[k]).collect()
}

/// `∫₀^u` of the linear interpolant of values at the nodes of `[0, 1]`.
fn cdf(values: &[f64], u: f64) -> f64 {
    let n = values.len();
    let h = 1.0 / (n - 1) as f64;
    let mut acc = 0.0;
    for j in 0..n - 1 {
        let t = ((u - j as f64 * h) / h).clamp(0.0, 1.0);
        if t <= 0.0 {
            break;
        }
        acc += h * (values[j] * t + (values[j + 1] - values[j]) * t * t / 2.0);
    }
    acc
}

/// Densities on the nodes of `[0, 1]`, each normalised by the trapezoid rule, weighted and summed.
fn mix(parts: &[(&Vec<f64>, f64)]) -> Vec<f64> {
    let n = parts[0].0.len();
    let mut out = vec![0.0; n];
    for (p, share) in parts {
        let total = (p.iter().sum::<f64>() - (p[0] + p[n - 1]) / 2.0) / (n - 1) as f64;
        if total > 0.0 {
            out.iter_mut().zip(p.iter()).for_each(|(o, &x)| *o += share * x / total);
        }
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn fields(
    description: &str,
    theta_i: &[f64],
    ndf: &Grid,
    sigma: &Grid,
    vndf: &[f32],
    luminance: &[f32],
    spectra: &Grid,
    opt: &Options,
) -> Vec<Field> {
    let (nt, v, s) = (theta_i.len(), opt.vndf, opt.spectra);
    let per_slice = |copies: usize| -> Vec<f32> {
        spectra
            .values
            .chunks_exact(s * s)
            .flat_map(|c| std::iter::repeat_n(c, copies).flatten().copied())
            .collect()
    };
    let values = |wavelengths: Vec<f32>| {
        let nl = wavelengths.len();
        vec![
            Field::f32("spectra", &[1, nt, nl, s, s], per_slice(nl)),
            Field::f32("wavelengths", &[nl], wavelengths),
        ]
    };
    let values = match opt.spectrum {
        Spectrum::Laser => values(vec![LASER_NM]),
        Spectrum::Visible => values(VISIBLE_NM.to_vec()),
        Spectrum::Rgb => vec![Field::f32("rgb", &[1, nt, 3, s, s], per_slice(3))],
    };
    vec![
        Field::u8("description", description.as_bytes().to_vec()),
        Field::u8("jacobian", vec![1]),
        Field::f32("theta_i", &[nt], theta_i.iter().map(|&t| t as f32).collect()),
        Field::f32("phi_i", &[1], vec![0.0]),
        Field::f32("ndf", &[opt.ndf, opt.ndf], ndf.values.clone()),
        Field::f32("sigma", &[opt.ndf, opt.ndf], sigma.values.clone()),
        Field::f32("vndf", &[1, nt, v, v], vndf.to_vec()),
        Field::f32("luminance", &[1, nt, s, s], luminance.to_vec()),
    ]
    .into_iter()
    .chain(values)
    .collect()
}

/// How closely a renderer reading the file gives back the BRDF.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Accuracy {
    /// Pairs compared (half drawn near the retro or the mirror direction).
    pub pairs: usize,
    /// Median, 95th percentile and largest `|table − f|/f` over them.
    pub median: f64,
    pub p95: f64,
    pub max: f64,
    /// Where the largest is, as `models.md` says a geometry: the light's
    /// `θi`, the viewer's `θo` and `Δφ` (degrees).
    pub worst_deg: [f64; 3],
    /// The largest `|table − f|/f` exactly at retroreflection, over incidences 0°–80°.
    pub retro_peak: f64,
}

/// The tolerances of a usable table (median, 95th percentile, retro peak),
/// under which export warns. The renderer's bars of `render-check` are
/// tighter, and narrow lobes miss them (docs/render.md).
pub const TOLERANCE: [f64; 3] = [0.02, 0.10, 0.05];
/// Pairs a written table is checked at, and the radius (degrees) of the
/// retro and mirror neighbourhoods a quarter of them each are drawn in.
pub const CHECK_PAIRS: usize = 4000;
pub const CHECK_LOBE_DEG: f64 = 3.0;

/// The file's `description`: where the values come from, at which
/// wavelengths, what is assumed, and which direction is the light (a
/// retroreflector's models are not reciprocal: docs/render.md).
pub fn description(origin: &str, spectrum: Spectrum) -> String {
    let values = match spectrum {
        Spectrum::Laser => format!("values at the head's laser wavelength, {LASER_NM} nm, held for every wavelength"),
        Spectrum::Visible => format!("values measured at {LASER_NM} nm and assumed grey over 360-830 nm"),
        Spectrum::Rgb => format!("values measured at {LASER_NM} nm and assumed grey in red, green and blue"),
    };
    format!("gonio: {origin}; {values}; isotropic; the viewer at the incidence (si.wi), the light at wo: f(l, v), not reciprocal")
}

impl Accuracy {
    pub fn within_tolerance(&self) -> bool {
        self.median <= TOLERANCE[0] && self.p95 <= TOLERANCE[1] && self.retro_peak <= TOLERANCE[2]
    }
}

/// A direction about `w` within `radius` (radians), uniform in the cone, kept in the upper hemisphere.
fn near(rng: &mut impl Rng, w: [f64; 3], radius: f64) -> [f64; 3] {
    loop {
        let cos_r = 1.0 - rng.random::<f64>() * (1.0 - radius.cos());
        let sin_r = (1.0 - cos_r * cos_r).max(0.0).sqrt();
        let phi = rng.random::<f64>() * 2.0 * PI;
        let t = normalize(if w[2].abs() < 0.9 {
            cross(w, [0.0, 0.0, 1.0])
        } else {
            cross(w, [1.0, 0.0, 0.0])
        });
        let b = cross(w, t);
        let d: [f64; 3] = std::array::from_fn(|k| cos_r * w[k] + sin_r * (phi.cos() * t[k] + phi.sin() * b[k]));
        if d[2] > 1e-3 {
            return d;
        }
    }
}

/// The largest polar angle of the pairs a table is judged at (degrees):
/// beyond it a renderer sees the material edge-on, where the table's
/// slices end ([`THETA_I_MAX_DEG`]) and `f·cos θ` vanishes.
pub const CHECK_THETA_MAX_DEG: f64 = 80.0;

/// A direction drawn in proportion to `cos θ` over `θ ≤ theta_max`.
fn cosine_weighted(rng: &mut impl Rng, theta_max: f64) -> [f64; 3] {
    let sin_t = (rng.random::<f64>()).sqrt() * theta_max.sin();
    unit(sin_t.asin(), rng.random::<f64>() * 2.0 * PI)
}

/// `n` direction pairs `(ωi, ωo)` drawn from `seed`, both within
/// [`CHECK_THETA_MAX_DEG`] of the normal, `ωi` in proportion to `cos θ`:
/// half with `ωo` drawn so too, over the whole hemisphere, as a renderer
/// meets them; a quarter within `lobe` (radians) of the retro direction
/// `ωi`, a quarter within it of the mirror direction.
pub fn pairs(n: usize, lobe: f64, seed: u64) -> Vec<([f64; 3], [f64; 3])> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let theta_max = CHECK_THETA_MAX_DEG.to_radians();
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let wi = cosine_weighted(&mut rng, theta_max);
        let wo = match out.len() % 4 {
            0 => near(&mut rng, wi, lobe),
            1 => near(&mut rng, [-wi[0], -wi[1], wi[2]], lobe),
            _ => cosine_weighted(&mut rng, theta_max),
        };
        if elevation(wo) <= theta_max {
            out.push((wi, wo));
        }
    }
    out
}

/// `|got − truth| / truth` sorted, where the truth is positive.
pub fn relative_errors(got: impl Iterator<Item = f64>, truth: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut errors: Vec<f64> = got.zip(truth).filter(|&(_, t)| t > 0.0).map(|(g, t)| (g - t).abs() / t).collect();
    errors.sort_by(f64::total_cmp);
    errors
}

/// The `p` quantile of sorted values (NaN if there are none).
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    sorted
        .get(((sorted.len() as f64 - 1.0) * p).round() as usize)
        .copied()
        .unwrap_or(f64::NAN)
}

/// Directions the retro peak is checked at: incidences 0°–80° by 0.0625°,
/// on the default slices and between them.
pub fn retro_directions() -> Vec<[f64; 3]> {
    (0..=1280).map(|k| unit((k as f64 * 0.0625).to_radians(), 0.3)).collect()
}

/// The geometry of a pair, as `models.md` says it: `(θi, θo, Δφ)` of the
/// light `ωo` and the viewer `ωi` (degrees).
pub fn geometry_deg(wi: [f64; 3], wo: [f64; 3]) -> [f64; 3] {
    let (l, v, dphi) = Directions::in_frame([0.0, 0.0, 1.0], wo, wi, [1.0, 0.0, 0.0]).angles();
    [l.to_degrees(), v.to_degrees(), dphi.to_degrees()]
}

/// Compares the table, read as the plugin reads it, with `brdf` at
/// [`pairs`] and at the retro peak.
pub fn accuracy(table: &Table, brdf: &Brdf, n: usize, lobe: f64) -> Accuracy {
    let drawn = pairs(n, lobe, 34);
    let got: Vec<f64> = drawn.par_iter().map(|&(wi, wo)| table.eval(wi, wo)).collect();
    let truth: Vec<f64> = drawn.par_iter().map(|&(wi, wo)| fr_cos(brdf, wi, wo)).collect();
    let worst = worst(&drawn, &got, &truth);
    let errors = relative_errors(got.into_iter(), truth.into_iter());
    let retro_peak = retro_directions()
        .into_iter()
        .map(|w| {
            let truth = fr_cos(brdf, w, w);
            (table.eval(w, w) - truth).abs() / truth
        })
        .fold(0.0, f64::max);
    Accuracy {
        pairs: errors.len(),
        median: quantile(&errors, 0.5),
        p95: quantile(&errors, 0.95),
        max: worst.0,
        worst_deg: worst.1,
        retro_peak,
    }
}

/// The largest `|got − truth|/truth` of `pairs` and the geometry it is at.
pub fn worst(pairs: &[([f64; 3], [f64; 3])], got: &[f64], truth: &[f64]) -> (f64, [f64; 3]) {
    pairs
        .iter()
        .zip(got.iter().zip(truth))
        .filter(|(_, (_, &t))| t > 0.0)
        .map(|(pair, (&g, &t))| ((g - t).abs() / t, pair))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map_or((f64::NAN, [f64::NAN; 3]), |(e, &(wi, wo))| (e, geometry_deg(wi, wo)))
}

#[cfg(test)]
mod tests;
