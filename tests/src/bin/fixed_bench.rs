//! `cargo run --release -p tests --bin fixed-bench`: accuracy of the head's
//! fixed-point models against the host's f64 models of `models.md`, as one
//! JSON object on stdout (a table on stderr).
//!
//! Grid: θi 0–85° step 1°, θo 0–89° step 1°, Δφ 0–180° step 2°. Models: the
//! three road markings of Spieringhs et al. Table 7 for `retro-phong` (view
//! cosine, as published) and `abc-retro` (back and view cosines), and a sharp
//! `retro-phong` lobe with exponent 10⁴. A point passes when
//! `|error| ≤ max(1e-3·|f|, 1e-4 sr⁻¹)`; `max_rel_err` is taken over the points
//! where the relative term is the larger (f ≥ 0.1 sr⁻¹), `max_abs_err` over the
//! others, and `violations` counts the points that fail.

use gonio_firmware::sanity::{FixedGeometry, FixedModel};
use gonio_host::brdf::{Directions, Material, ModelId, Param};
use gonio_shared::{Geometry, SanityKind, SanityModel};
use std::time::Instant;

struct Case {
    name: &'static str,
    host: Material,
    device: SanityModel,
}

fn retro_phong(name: &'static str, p: [f64; 6]) -> Case {
    let f = p.map(|x| x as f32);
    Case {
        name,
        host: Material {
            model: ModelId::RetroPhong,
            params: p.to_vec(),
            param: Param::View,
        },
        device: SanityModel::from_params(SanityKind::RetroPhong, &f).expect("six parameters"),
    }
}

fn abc(name: &'static str, p: [f64; 8], param: Param) -> Case {
    let f = p.map(|x| x as f32);
    Case {
        name,
        host: Material {
            model: ModelId::AbcRetro,
            params: p.to_vec(),
            param,
        },
        device: SanityModel::from_params(
            SanityKind::AbcRetro {
                back: param == Param::Back,
            },
            &f,
        )
        .expect("eight parameters"),
    }
}

fn main() {
    // The f32 parameters the head receives are what the host model evaluates too.
    let q = |p: &[f64]| p.iter().map(|x| *x as f32 as f64).collect::<Vec<_>>();
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
    let mut cases = Vec::new();
    for (n, p) in names.iter().zip(rm_rp) {
        cases.push(retro_phong(n, p));
    }
    for param in [Param::Back, Param::View] {
        for (n, p) in names.iter().zip(rm_abc) {
            cases.push(abc(n, p, param));
        }
    }
    cases.push(retro_phong("sharp lobe n = 1e4", [0.05, 1.0e4, 0.8, 0.1, 0.02, 3.0]));
    for c in &mut cases {
        c.host.params = q(&c.host.params);
    }

    let grid: Vec<(f32, f32, f32)> = (0..=85)
        .flat_map(|ti| (0..=89).flat_map(move |to| (0..=90).map(move |dp| (ti as f32, to as f32, 2.0 * dp as f32))))
        .collect();
    let (mut max_rel, mut max_abs, mut violations, mut points) = (0.0f64, 0.0f64, 0u64, 0u64);
    let mut eval_time = 0.0;
    eprintln!("fixed-point models vs f64 over {} geometries", grid.len());
    for c in &cases {
        let model = FixedModel::new(&c.device).expect("Table 7 parameters are accepted");
        let geos: Vec<FixedGeometry> = grid
            .iter()
            .map(|&(a, b, d)| FixedGeometry::from_degrees(&Geometry::new(a, b, d)).expect("finite"))
            .collect();
        let t = Instant::now();
        let fixed: Vec<f64> = geos.iter().map(|g| model.eval(g).to_f32() as f64).collect();
        eval_time += t.elapsed().as_secs_f64();
        let (mut c_rel, mut c_abs, mut c_bad) = (0.0f64, 0.0f64, 0u64);
        for (&(a, b, d), fx) in grid.iter().zip(&fixed) {
            let f = c.host.eval(&Directions::from_degrees(a as f64, b as f64, d as f64));
            let err = (fx - f).abs();
            if f.abs() >= 0.1 {
                c_rel = c_rel.max(err / f.abs());
            } else {
                c_abs = c_abs.max(err);
            }
            if err > (1e-3 * f.abs()).max(1e-4) {
                c_bad += 1;
            }
        }
        eprintln!(
            "  {:<11} {:<7} {:<20} max rel {:.2e}  max abs {:.2e}  violations {}",
            c.host.model.name(),
            format!("{:?}", c.host.param).to_lowercase(),
            c.name,
            c_rel,
            c_abs,
            c_bad
        );
        max_rel = max_rel.max(c_rel);
        max_abs = max_abs.max(c_abs);
        violations += c_bad;
        points += grid.len() as u64;
    }
    let out = serde_json::json!({
        "max_rel_err": max_rel,
        "max_abs_err": max_abs,
        "violations": violations,
        "points": points,
        "models": cases.len(),
        "evals_per_s": points as f64 / eval_time,
    });
    println!("{out}");
}
