//! Synthetic BRDF data for the fitting tests and `fit-bench`: geometries of
//! the Belcour grid (θi 15/30/60°, θo 0–87° step 3°, Δφ step 10°; θo = 90°
//! is grazing and left out), values of a known material times `1 + noise·N(0,1)`.

use gonio_analysis::fit::{Dataset, Observation, Units};
use gonio_brdf::{Directions, Material, ModelId, Param};
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;

/// Parameters each model is recovered from: Spieringhs Table 7 (road
/// marking 1) where the model is there, Zhang's khaki paint for
/// `five-param`, plausible values for `lambert` and `lafortune`.
pub fn reference(model: ModelId) -> Material {
    let params = match model {
        ModelId::Lambert => vec![0.5],
        ModelId::RetroPhong => vec![0.620, 24.0, 0.158, 0.0415, 0.00133, 5.47],
        ModelId::AbcRetro => vec![0.534, 0.0472, 1.82, 13.5, 1.51, 1.02, 0.0775, 6.97],
        ModelId::AbcRetroPerLobe => vec![0.534, 0.0472, 1.82, 13.5, 1.51, 0.5, 1.02, 0.0775, 6.97],
        ModelId::BeckmannRetro => vec![0.796, 8.20, 0.995],
        ModelId::BlinnRetro => vec![0.919, 7.91e3, 2.77e3],
        ModelId::Lafortune => vec![0.5, -1.0, 1.0, 20.0, 1.0, 1.0, 150.0],
        ModelId::OrenNayar => vec![0.268, 0.865],
        ModelId::FiveParam => vec![0.0698, 0.478, 0.777, -28.935, 0.107],
    };
    Material {
        model,
        params,
        param: Param::View,
    }
}

/// The distinct geometries of the grid, in radians.
pub fn belcour_geometries() -> Vec<(f64, f64, f64)> {
    let mut g = Vec::new();
    for ti in [15.0f64, 30.0, 60.0] {
        for k in 0..30 {
            for j in 0..36 {
                g.push((
                    ti.to_radians(),
                    (3.0 * k as f64).to_radians(),
                    (-180.0 + 10.0 * j as f64).to_radians(),
                ));
            }
        }
    }
    g
}

/// A dense grid (θi 15/30/60°, θo 0–86° step 1°, Δφ step 4°): the
/// geometries of a measured file of tens of thousands of samples.
pub fn dense_geometries() -> Vec<(f64, f64, f64)> {
    let mut g = Vec::new();
    for ti in [15.0f64, 30.0, 60.0] {
        for k in 0..87 {
            for j in 0..90 {
                g.push((ti.to_radians(), (k as f64).to_radians(), (-180.0 + 4.0 * j as f64).to_radians()));
            }
        }
    }
    g
}

/// A material outside every model: two retro lobes of different widths
/// (a narrow core, n = 400, and a broad one, n = 12) over a diffuse floor,
/// with a weak mirror lobe, as a bead layer's core and halo.
pub fn two_lobes(d: &Directions) -> f64 {
    let core = Material::parse(ModelId::RetroPhong, "kd=0.3,n=400,k1=0.6,k2=0.05,k3=0.01,k4=2").expect("valid");
    let halo = Material::parse(ModelId::RetroPhong, "kd=0,n=12,k1=0.2,k2=0.1,k3=0,k4=0").expect("valid");
    core.eval(d) + halo.eval(d)
}

/// `n` samples at grid geometries (cycled), `f_r` with multiplicative noise.
pub fn samples(material: &Material, n: usize, noise: f64, seed: u64) -> Dataset {
    samples_of(|d| material.eval(d), &belcour_geometries(), n, noise, seed)
}

/// `n` samples of any BRDF at `geos` (cycled), with multiplicative noise.
pub fn samples_of(brdf: impl Fn(&Directions) -> f64, geos: &[(f64, f64, f64)], n: usize, noise: f64, seed: u64) -> Dataset {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let observations = (0..n)
        .map(|k| {
            let (theta_i, theta_o, dphi) = geos[k % geos.len()];
            let mut o = Observation {
                theta_i,
                theta_o,
                dphi,
                value: 0.0,
                sigma: None,
                shared: Default::default(),
            };
            let f = brdf(&o.directions());
            let e: f64 = rng.sample(StandardNormal);
            o.value = f * (1.0 + noise * e);
            o.sigma = Some((noise * f).max(1e-12));
            o
        })
        .collect();
    Dataset::new(Units::Fr, observations)
}
