//! Belcour et al. 2014 eq. 5 over linear triangles, exactly: the integrand
//! `(x − μx)^i (y − μy)^j f` is a polynomial of degree at most 5 on each
//! piece, which Dunavant's 7-point rule integrates without error.

use super::mesh::Node;

/// The highest order of the central moments.
pub const ORDER: usize = 4;

/// `∫ f`, the mean `(μx, μy)` and `μ_{i,j}` for `i + j ≤ ORDER`, each
/// normalised by `∫ f` (`central[i][j]`; `central[0][0] = 1`).
#[derive(Debug, Clone, PartialEq)]
pub struct Integrals {
    pub norm: f64,
    pub mean: [f64; 2],
    pub central: [[f64; ORDER + 1]; ORDER + 1],
}

/// Dunavant (1985), degree 5: barycentric points and weights summing to 1.
const RULE: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.059_715_871_789_770;
    const B1: f64 = 0.470_142_064_105_115;
    const W1: f64 = 0.132_394_152_788_506;
    const A2: f64 = 0.797_426_985_353_087;
    const B2: f64 = 0.101_286_507_323_456;
    const W2: f64 = 0.125_939_180_544_827;
    const C: f64 = 1.0 / 3.0;
    [
        ([C, C, C], 0.225),
        ([A1, B1, B1], W1),
        ([B1, A1, B1], W1),
        ([B1, B1, A1], W1),
        ([A2, B2, B2], W2),
        ([B2, A2, B2], W2),
        ([B2, B2, A2], W2),
    ]
};

/// `∫ g(x, y) f(x, y) dx dy` over the pieces.
fn integral(pieces: &[[Node; 3]], g: impl Fn(f64, f64) -> f64) -> f64 {
    pieces
        .iter()
        .map(|piece| {
            let [a, b, c] = piece;
            let sum: f64 = RULE
                .iter()
                .map(|(w, weight)| {
                    let at = |k: usize| w[0] * a.p[k] + w[1] * b.p[k] + w[2] * c.p[k];
                    weight * g(at(0), at(1)) * (w[0] * a.f + w[1] * b.f + w[2] * c.f)
                })
                .sum();
            Node::area(piece) * sum
        })
        .sum()
}

/// The moments of `f` over the pieces; `None` when `∫ f` is not positive.
pub fn moments(pieces: &[[Node; 3]]) -> Option<Integrals> {
    let norm = integral(pieces, |_, _| 1.0);
    if norm.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mean = [integral(pieces, |x, _| x) / norm, integral(pieces, |_, y| y) / norm];
    let mut central = [[0.0; ORDER + 1]; ORDER + 1];
    for (i, row) in central.iter_mut().enumerate() {
        for (j, m) in row.iter_mut().enumerate().take(ORDER + 1 - i) {
            *m = integral(pieces, |x, y| (x - mean[0]).powi(i as i32) * (y - mean[1]).powi(j as i32)) / norm;
        }
    }
    Some(Integrals { norm, mean, central })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(x: f64, y: f64, f: f64) -> Node {
        Node { p: [x, y], f }
    }

    #[test]
    fn a_uniform_square_has_the_moments_of_its_area() {
        // f = 2 on [0, 2] × [0, 1]: mean (1, 0.5), μ20 = 4/12, μ02 = 1/12,
        // μ40 = 2⁴/80, μ11 = 0, μ22 = μ20·μ02.
        let (a, b, c, d) = (node(0.0, 0.0, 2.0), node(2.0, 0.0, 2.0), node(2.0, 1.0, 2.0), node(0.0, 1.0, 2.0));
        let m = moments(&[[a, b, c], [a, c, d]]).unwrap();
        assert!((m.norm - 4.0).abs() < 1e-12);
        assert!((m.mean[0] - 1.0).abs() < 1e-12 && (m.mean[1] - 0.5).abs() < 1e-12);
        assert!((m.central[2][0] - 1.0 / 3.0).abs() < 1e-12);
        assert!((m.central[0][2] - 1.0 / 12.0).abs() < 1e-12);
        assert!(m.central[1][1].abs() < 1e-12);
        assert!((m.central[4][0] - 16.0 / 80.0).abs() < 1e-12);
        assert!((m.central[2][2] - 1.0 / 36.0).abs() < 1e-12);
        assert!((m.central[0][0] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_ramp_shifts_the_mean_as_its_weight_says() {
        // f = x on the triangle (0,0), (1,0), (0,1): ∫f = 1/6, ∫x f = 1/12 → μx = 1/2.
        let m = moments(&[[node(0.0, 0.0, 0.0), node(1.0, 0.0, 1.0), node(0.0, 1.0, 0.0)]]).unwrap();
        assert!((m.norm - 1.0 / 6.0).abs() < 1e-12);
        assert!((m.mean[0] - 0.5).abs() < 1e-12 && (m.mean[1] - 0.25).abs() < 1e-12);
        assert!(moments(&[]).is_none());
    }
}
