//! Coefficients of retroreflection from a BRDF (`docs/retroreflection.md`):
//! `R_A = f_r·cosθi·cosθo` (cd·lx⁻¹·m⁻², CIE 54.2 / ASTM E808–E810) and
//! `R_L = f_r·cosθi` (mcd·m⁻²·lx⁻¹ after ×1000, EN 1436 / ASTM E1710), at
//! the geometries of the CIE angle system, averaged over the source and
//! receiver apertures, each with its standard uncertainty. Values are at
//! the laser's wavelength (633 nm), not photometric.

pub mod angles;
pub mod aperture;
pub mod asked;
pub mod fit_files;
pub mod json;
pub mod provenance;
pub mod scan;
mod source;
pub mod text;

pub use angles::Cie;
pub use aperture::Apertures;
pub use asked::Asked;
pub use provenance::{Basis, Provenance, Support};
pub use source::{best, head_apertures, Estimate, Fitted, ModelValue, Nearest, Source, COMPARABLE_RMSE_RATIO};

use anyhow::{bail, Result};
use serde::Serialize;

/// Wavelength the head measures at (nm): the coefficients are spectral
/// values at this wavelength, not weighted by V(λ) and illuminant A.
pub const WAVELENGTH_NM: f64 = 633.0;

/// Which coefficient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// `R_A = f_r·cosθi·cosθo`, cd·lx⁻¹·m⁻².
    Ra,
    /// `R_L = 1000·f_r·cosθi`, mcd·m⁻²·lx⁻¹.
    Rl,
}

impl Kind {
    /// The coefficient's integrand per unit `f_r`, in its reporting unit.
    pub fn factor(self, cos_i: f64, cos_o: f64) -> f64 {
        match self {
            Kind::Ra => cos_i * cos_o,
            Kind::Rl => 1000.0 * cos_i,
        }
    }

    pub fn unit(self) -> &'static str {
        match self {
            Kind::Ra => "cd·lx⁻¹·m⁻²",
            Kind::Rl => "mcd·m⁻²·lx⁻¹",
        }
    }
}

/// One requested coefficient: what, where, through which apertures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Request {
    pub kind: Kind,
    pub geometry: Cie,
    pub apertures: Apertures,
}

/// ASTM E809/E810 source and receiver: discs of 10′ seen from the sample
/// (the instrument's angular apertures; a project default, change with
/// `--source-aperture-deg` / `--receiver-aperture-deg`).
pub const ASTM_APERTURES: Apertures = Apertures {
    source_deg: 10.0 / 60.0,
    receiver_deg: 10.0 / 60.0,
};

/// EN 1436 / ASTM E1710 road-marking retroreflectometers: 0.33° apertures.
pub const EN1436_APERTURES: Apertures = Apertures {
    source_deg: 0.33,
    receiver_deg: 0.33,
};

/// The 30 m road-marking geometry (EN 1436, ASTM E1710): headlamp 0.65 m
/// and eye 1.2 m above the road, 30 m away.
pub const EN1436_ENTRANCE_DEG: f64 = 88.76;
pub const EN1436_OBSERVATION_DEG: f64 = 1.05;

/// Observation, entrance and rotation angles of the `astm-e810` set.
pub const ASTM_ALPHAS: [f64; 7] = [0.1, 0.2, 0.33, 0.5, 1.0, 1.5, 2.0];
pub const ASTM_BETAS: [f64; 5] = [-4.0, 15.0, 30.0, 40.0, 45.0];
pub const ASTM_EPSILONS: [f64; 2] = [0.0, 90.0];

/// A named set of geometries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Set {
    /// R_A, coplanar: α ∈ {0.1, 0.2, 0.33, 0.5, 1, 1.5, 2}° × β ∈ {−4, 15, 30, 40, 45}° × ε ∈ {0, 90}°, 10′ apertures.
    AstmE810,
    /// R_L at the 30 m geometry: entrance 88.76°, observation 1.05°, 0.33° apertures.
    En1436,
}

impl Set {
    pub fn requests(self) -> Vec<Request> {
        match self {
            Set::AstmE810 => grid(&ASTM_ALPHAS, &ASTM_BETAS, &ASTM_EPSILONS, ASTM_APERTURES),
            Set::En1436 => vec![Request {
                kind: Kind::Rl,
                geometry: Cie::coplanar(EN1436_OBSERVATION_DEG, EN1436_ENTRANCE_DEG, 0.0),
                apertures: EN1436_APERTURES,
            }],
        }
    }
}

/// The table of a report: the `astm-e810` set at ε = 0 (an isotropic BRDF
/// gives the same at every ε) and `en1436`'s R_L.
pub fn report_requests() -> Vec<Request> {
    let mut r: Vec<Request> = Set::AstmE810
        .requests()
        .into_iter()
        .filter(|r| r.geometry.epsilon_deg == 0.0)
        .collect();
    r.extend(Set::En1436.requests());
    r
}

/// R_A on the grid `α × β × ε` (coplanar).
pub fn grid(alphas: &[f64], betas: &[f64], epsilons: &[f64], apertures: Apertures) -> Vec<Request> {
    let mut out = Vec::new();
    for &b in betas {
        for &a in alphas {
            for &e in epsilons {
                out.push(Request {
                    kind: Kind::Ra,
                    geometry: Cie::coplanar(a, b, e),
                    apertures,
                });
            }
        }
    }
    out
}

/// Checks a request: angles finite, the directions in front of the sample.
pub fn validate(r: &Request) -> Result<()> {
    let g = &r.geometry;
    let all = [
        g.alpha_deg,
        g.beta1_deg,
        g.beta2_deg,
        g.epsilon_deg,
        r.apertures.source_deg,
        r.apertures.receiver_deg,
    ];
    if all.iter().any(|x| !x.is_finite()) {
        bail!("angles and apertures must be finite numbers");
    }
    if !(0.0..=10.0).contains(&g.alpha_deg) {
        bail!("observation angle α = {}° must be in [0°, 10°]", g.alpha_deg);
    }
    if r.apertures.source_deg < 0.0 || r.apertures.receiver_deg < 0.0 || r.apertures.source_deg > 5.0 || r.apertures.receiver_deg > 5.0 {
        bail!("apertures must be in [0°, 5°]");
    }
    let [ti, to, _] = g.sample_angles_deg();
    let margin = (r.apertures.source_deg.max(r.apertures.receiver_deg)) / 2.0;
    if ti + margin >= 90.0 || to + margin >= 90.0 {
        bail!(
            "entrance β = {}° with α = {}°: θi = {ti:.2}°, θo = {to:.2}°, the apertures reach behind the sample",
            g.beta_deg(),
            g.alpha_deg
        );
    }
    Ok(())
}

/// A computed coefficient.
#[derive(Debug, Clone, Serialize)]
pub struct Coefficient {
    pub request: Request,
    /// `(θi, θo, Δφ)` of the nominal directions (degrees).
    pub sample_angles_deg: [f64; 3],
    pub estimate: Estimate,
}

/// Every request evaluated on a source.
pub fn compute(source: &Source, requests: &[Request]) -> Result<Vec<Coefficient>> {
    requests
        .iter()
        .map(|r| {
            validate(r)?;
            Ok(Coefficient {
                request: *r,
                sample_angles_deg: r.geometry.sample_angles_deg(),
                estimate: source.estimate(r)?,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use gonio_brdf::{Material, ModelId};

    fn lambert() -> Source {
        Source::model(Material::parse(ModelId::Lambert, "kd=0.5").unwrap())
    }

    /// Lambertian kd = 0.5 → R_A(0.2°, −4°) ≈ 0.15838 (0.15834
    /// with the observer beyond the beam, as here), R_L ≈ 3.444.
    #[test]
    fn lambertian_coefficients_by_hand() {
        let ra = compute(&lambert(), &grid(&[0.2], &[-4.0], &[0.0], ASTM_APERTURES)).unwrap();
        let v = ra[0].estimate.value;
        let exact = 0.5 / std::f64::consts::PI * 4f64.to_radians().cos() * 4.2f64.to_radians().cos();
        assert!((v - exact).abs() < 1e-6, "{v} vs {exact}");
        assert!((v - 0.15838).abs() < 1e-3);
        let rl = compute(&lambert(), &Set::En1436.requests()).unwrap();
        let v = rl[0].estimate.value;
        assert!((v - 3.444).abs() < 1e-3, "R_L {v}");
        assert_eq!(rl[0].request.kind, Kind::Rl);
    }

    #[test]
    fn the_named_sets_are_valid() {
        for s in [Set::AstmE810, Set::En1436] {
            for r in s.requests() {
                validate(&r).unwrap();
            }
        }
        assert_eq!(Set::AstmE810.requests().len(), 70);
    }

    #[test]
    fn geometries_behind_the_sample_are_refused() {
        let r = Request {
            kind: Kind::Ra,
            geometry: Cie::coplanar(2.0, 89.95, 0.0),
            apertures: ASTM_APERTURES,
        };
        assert!(validate(&r).is_err());
    }

    /// A lobe narrower than the apertures: the averaged value is well below
    /// the point value, and equals it for point apertures.
    #[test]
    fn aperture_averaging_matters_on_a_narrow_lobe() {
        let narrow = Material::parse(ModelId::RetroPhong, "kd=0.05,n=100000,k1=0.8,k2=0.1,k3=0,k4=0").unwrap();
        let src = Source::model(narrow);
        let at = |ap| compute(&src, &grid(&[0.1], &[5.0], &[0.0], ap)).unwrap()[0].estimate.value;
        let (point, averaged) = (at(Apertures::POINT), at(ASTM_APERTURES));
        assert!(averaged < 0.95 * point, "averaged {averaged} vs point {point}");
        let wide = Material::parse(ModelId::RetroPhong, "kd=0.05,n=50,k1=0.8,k2=0.1,k3=0,k4=0").unwrap();
        let src = Source::model(wide);
        let at = |ap| compute(&src, &grid(&[0.1], &[5.0], &[0.0], ap)).unwrap()[0].estimate.value;
        assert!((at(ASTM_APERTURES) / at(Apertures::POINT) - 1.0).abs() < 1e-3);
    }
}
