//! `cargo run --release -p gonio-bench --bin fixed-bench`: accuracy of the head's
//! fixed-point models against the host's f64 models of `models.md`, as one
//! JSON object on stdout (a table on stderr): every case of
//! `gonio_tests::fixed_agreement` over its whole grid (`cargo test` checks a
//! sample of it). `max_rel_err` is taken over the points where the relative
//! term is the larger (f ≥ 0.1 sr⁻¹), `max_abs_err` over the others, and
//! `violations` counts the points that fail.

use gonio_tests::fixed_agreement::{cases, grid};
use std::time::Instant;

fn main() {
    let cases = cases();
    let grid = grid();
    let (mut max_rel, mut max_abs, mut violations, mut points) = (0.0f64, 0.0f64, 0u64, 0u64);
    let mut eval_time = 0.0;
    eprintln!("fixed-point models vs f64 over {} geometries", grid.len());
    for c in &cases {
        let (model, geos) = c.prepare(&grid);
        let t = Instant::now();
        let fixed: Vec<f64> = geos.iter().map(|g| model.eval(g).to_f32() as f64).collect();
        eval_time += t.elapsed().as_secs_f64();
        let a = c.compare(&grid, &fixed);
        eprintln!(
            "  {:<11} {:<7} {:<20} max rel {:.2e}  max abs {:.2e}  violations {}",
            c.host.model.name(),
            format!("{:?}", c.host.param).to_lowercase(),
            c.name,
            a.max_rel,
            a.max_abs,
            a.violations
        );
        max_rel = max_rel.max(a.max_rel);
        max_abs = max_abs.max(a.max_abs);
        violations += a.violations;
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
