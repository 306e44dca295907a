//! The head's fixed-point sanity models agree with the host's f64 models
//! (`models.md`) on a sample of `fixed-bench`'s grid: every 13th geometry
//! (some 54 000 points per case) and the retro and mirror peaks, every case,
//! no point outside the tolerance.

use gonio_tests::fixed_agreement::{cases, grid};

#[test]
fn fixed_point_models_agree_with_the_f64_models() {
    let full = grid();
    let mut sample: Vec<(f32, f32, f32)> = full.iter().step_by(13).copied().collect();
    // The peaks, where the lobes are narrowest: retroreflection and the mirror direction.
    for ti in [0.0, 15.0, 30.0, 60.0, 85.0] {
        sample.push((ti, ti, 0.0));
        sample.push((ti, ti, 180.0));
    }
    for c in cases() {
        let (model, geos) = c.prepare(&sample);
        let fixed: Vec<f64> = geos.iter().map(|g| model.eval(g).to_f32() as f64).collect();
        let a = c.compare(&sample, &fixed);
        assert_eq!(
            a.violations,
            0,
            "{} {:?} {}: {} of {} points outside max(1e-3·f, 1e-4 sr⁻¹) (max rel {:.2e}, max abs {:.2e})",
            c.host.model.name(),
            c.host.param,
            c.name,
            a.violations,
            sample.len(),
            a.max_rel,
            a.max_abs
        );
        assert!(a.max_rel > 0.0, "{}: the comparison saw no lit point", c.name);
    }
}
