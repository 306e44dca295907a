//! The head's fixed-point sanity models against the host's f64 models of
//! `models.md`: the cases and the comparison, shared by `fixed-bench` (the
//! full sweep) and `cargo test` (`tests/fixed_point.rs`, a sample of it), so
//! an edit to either side of the models is caught by the test command.
//!
//! Cases: the three road markings of Spieringhs et al. Table 7 for
//! `retro-phong` (view cosine, as published) and `abc-retro` (back and view
//! cosines), and a sharp `retro-phong` lobe with exponent 10⁴. A point passes
//! when `|error| ≤ max(1e-3·|f|, 1e-4 sr⁻¹)`.

use gonio_brdf::{Directions, Material, ModelId, Param};
use gonio_firmware::sanity::{FixedGeometry, FixedModel};
use gonio_shared::{Geometry, SanityKind, SanityModel};

/// One material, as the host fits it and as the head receives it.
pub struct Case {
    pub name: &'static str,
    pub host: Material,
    pub device: SanityModel,
}

/// How one case compares over a grid.
#[derive(Debug, Clone, Copy, Default)]
pub struct Agreement {
    /// Largest relative error where `f ≥ 0.1 sr⁻¹` (the relative term rules).
    pub max_rel: f64,
    /// Largest absolute error elsewhere.
    pub max_abs: f64,
    /// Points that fail the tolerance.
    pub violations: u64,
}

/// The sweep's grid: θi 0–85° step 1°, θo 0–89° step 1°, Δφ 0–180° step 2°
/// (degrees, as the head receives them).
pub fn grid() -> Vec<(f32, f32, f32)> {
    (0..=85)
        .flat_map(|ti| (0..=89).flat_map(move |to| (0..=90).map(move |dp| (ti as f32, to as f32, 2.0 * dp as f32))))
        .collect()
}

/// Every case; the host's parameters are the f32 values the head receives.
pub fn cases() -> Vec<Case> {
    let rm_rp = [
        [0.620, 24.0, 0.158, 0.0415, 0.00133, 5.47],
        [0.594, 24.0, 0.0696, 0.0733, 6.58e-05, 8.74],
        [0.701, 68.0, 0.184, 1.53e-12, 0.00570, 3.40],
    ];
    let rm_abc = [
        [0.534, 0.0472, 1.82, 13.5, 1.51, 1.02, 0.0775, 6.97],
        [0.0303, 0.140, 1.59, 32.6, 1.08, 1.19, 0.00779, 0.0179],
        [0.747, 0.00466, 6.66, 37.8, 0.710, 3.58, 22.9, 0.729],
    ];
    let names = ["road marking 1", "road marking 2", "road marking 3"];
    let mut cases: Vec<Case> = names
        .iter()
        .zip(&rm_rp)
        .map(|(n, p)| case(n, ModelId::RetroPhong, p, Param::View))
        .collect();
    for param in [Param::Back, Param::View] {
        cases.extend(names.iter().zip(&rm_abc).map(|(n, p)| case(n, ModelId::AbcRetro, p, param)));
    }
    cases.push(case(
        "sharp lobe n = 1e4",
        ModelId::RetroPhong,
        &[0.05, 1.0e4, 0.8, 0.1, 0.02, 3.0],
        Param::View,
    ));
    cases
}

fn case(name: &'static str, model: ModelId, p: &[f64], param: Param) -> Case {
    let f: Vec<f32> = p.iter().map(|&x| x as f32).collect();
    let kind = match model {
        ModelId::RetroPhong => SanityKind::RetroPhong,
        _ => SanityKind::AbcRetro {
            back: param == Param::Back,
        },
    };
    Case {
        name,
        host: Material {
            model,
            params: f.iter().map(|&x| x as f64).collect(),
            param,
        },
        device: SanityModel::from_params(kind, &f).expect("the model's parameter count"),
    }
}

impl Case {
    /// The head's model prepared for evaluation, and the grid's geometries
    /// as the head sees them (what the benchmark times).
    pub fn prepare(&self, grid: &[(f32, f32, f32)]) -> (FixedModel, Vec<FixedGeometry>) {
        let model = FixedModel::new(&self.device).expect("Table 7 parameters are accepted");
        let geos = grid
            .iter()
            .map(|&(a, b, d)| FixedGeometry::from_degrees(&Geometry::new(a, b, d)).expect("finite"))
            .collect();
        (model, geos)
    }

    /// The fixed-point values `fixed` (at `grid`) against the host's model.
    pub fn compare(&self, grid: &[(f32, f32, f32)], fixed: &[f64]) -> Agreement {
        let mut out = Agreement::default();
        for (&(a, b, d), fx) in grid.iter().zip(fixed) {
            let f = self.host.eval(&Directions::from_degrees(a as f64, b as f64, d as f64));
            let err = (fx - f).abs();
            if f.abs() >= 0.1 {
                out.max_rel = out.max_rel.max(err / f.abs());
            } else {
                out.max_abs = out.max_abs.max(err);
            }
            if err > (1e-3 * f.abs()).max(1e-4) {
                out.violations += 1;
            }
        }
        out
    }
}
