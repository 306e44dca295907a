//! Mitsuba's continuous marginal warp (`Marginal2D<Float, D, true>` of
//! `mitsuba/core/distr_2d.h`, pbrt-v4's `PiecewiseLinear2D`), as the
//! `measured` plugin builds it from a `.bsdf` file: a density given at the
//! nodes of a regular grid over the unit square and interpolated bilinearly,
//! sampled through its marginal in `y` and then its conditional in `x`, per
//! slice of a parameter axis, with the slices' CDFs interpolated linearly
//! between the two nearest parameter values.
//!
//! The exporter needs the forward map (`sample`) to know which direction each
//! node of the spectra grid stands for, and the inverse (`invert`) to predict
//! what a renderer will read back; both follow the C++ step by step (same
//! tables, same segment formulas), in f64. Only one parameter axis is kept:
//! the file's `phi_i` and `wavelengths` axes are of size one (isotropic, one
//! wavelength), which the plugin handles with a weight of one on the only
//! slice.

/// A density on an `w × h` node grid over `[0, 1]²`, one slice per parameter value.
#[derive(Debug, Clone)]
pub struct Marginal {
    w: usize,
    h: usize,
    params: Vec<f64>,
    /// Node densities, normalised per slice (slice-major, then row `y`, then `x`).
    data: Vec<f64>,
    /// Per slice, the marginal CDF at the end of each row interval (`h − 1`).
    marg: Vec<f64>,
    /// Per slice and row, the conditional CDF at the end of each column interval (`w − 1`).
    cond: Vec<f64>,
}

/// The slice below a parameter value and the weights of it and the next one.
#[derive(Debug, Clone, Copy)]
struct Weights {
    slice: usize,
    w0: f64,
    w1: f64,
}

/// Mitsuba's `interpolate_weights`: the interval of `params` holding `p`, clamped.
fn weights(params: &[f64], p: f64) -> Weights {
    let n = params.len();
    if n == 1 {
        return Weights {
            slice: 0,
            w0: 1.0,
            w1: 0.0,
        };
    }
    let i = params[..n - 1].iter().rposition(|&q| q < p).unwrap_or(0).min(n - 2);
    let (p0, p1) = (params[i], params[i + 1]);
    let w1 = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
    Weights {
        slice: i,
        w0: 1.0 - w1,
        w1,
    }
}

/// The patch of a `w × h` node grid over `[0, 1]²` that holds `point`
/// (clamped into the square), and the fractions of the way across it.
fn patch(point: [f64; 2], w: usize, h: usize) -> (usize, usize, f64, f64) {
    let (px, py) = (point[0].clamp(0.0, 1.0) * (w - 1) as f64, point[1].clamp(0.0, 1.0) * (h - 1) as f64);
    let (col, row) = ((px as usize).min(w - 2), (py as usize).min(h - 2));
    (col, row, px - col as f64, py - row as f64)
}

impl Marginal {
    /// From `values` (one `h × w` block per parameter value, ascending
    /// `params`), normalising each slice to integrate to one as the plugin does.
    pub fn new(values: &[f32], w: usize, h: usize, params: &[f64]) -> Self {
        assert!(w >= 2 && h >= 2 && !params.is_empty() && values.len() == w * h * params.len());
        let (sx, sy) = (0.5 / (w - 1) as f64, 0.5 / (h - 1) as f64);
        let mut data = Vec::with_capacity(values.len());
        let mut marg = Vec::with_capacity(params.len() * (h - 1));
        let mut cond = Vec::with_capacity(params.len() * h * (w - 1));
        for slice in values.chunks_exact(w * h) {
            let start = cond.len();
            let mut row_total = Vec::with_capacity(h);
            for row in slice.chunks_exact(w) {
                let mut acc = 0.0;
                for pair in row.windows(2) {
                    acc += sx * (pair[0] as f64 + pair[1] as f64);
                    cond.push(acc);
                }
                row_total.push(acc);
            }
            let mstart = marg.len();
            let mut acc = 0.0;
            for pair in row_total.windows(2) {
                acc += sy * (pair[0] + pair[1]);
                marg.push(acc);
            }
            let norm = if acc > 0.0 { 1.0 / acc } else { 1.0 };
            cond[start..].iter_mut().for_each(|c| *c *= norm);
            marg[mstart..].iter_mut().for_each(|m| *m *= norm);
            data.extend(slice.iter().map(|&v| v as f64 * norm));
        }
        Marginal {
            w,
            h,
            params: params.to_vec(),
            data,
            marg,
            cond,
        }
    }

    fn lookup(table: &[f64], per_slice: usize, idx: usize, wt: Weights) -> f64 {
        let v0 = table[wt.slice * per_slice + idx];
        if wt.w1 == 0.0 {
            return v0 * wt.w0;
        }
        v0 * wt.w0 + table[(wt.slice + 1) * per_slice + idx] * wt.w1
    }

    fn data_at(&self, x: usize, y: usize, wt: Weights) -> f64 {
        Self::lookup(&self.data, self.w * self.h, y * self.w + x, wt)
    }

    fn marg_at(&self, row: usize, wt: Weights) -> f64 {
        Self::lookup(&self.marg, self.h - 1, row, wt)
    }

    fn cond_at(&self, row: usize, col: usize, wt: Weights) -> f64 {
        Self::lookup(&self.cond, self.h * (self.w - 1), row * (self.w - 1) + col, wt)
    }

    /// The fraction of a segment whose linear density goes from `v0` to
    /// `v1` that holds `mass` (`sample_segment`).
    fn sample_segment(mass: f64, inv_width: f64, v0: f64, v1: f64) -> f64 {
        let non_const = (v0 - v1).abs() > 1e-4 * (v0 + v1);
        let divisor = if non_const { v0 - v1 } else { v0 + v1 };
        let mut s = mass * 2.0 * inv_width;
        if non_const {
            s = v0 - (v0 * v0 + s * (v1 - v0)).max(0.0).sqrt();
        }
        if divisor != 0.0 {
            s /= divisor;
        }
        s
    }

    /// The mass of the first fraction `t` of such a segment (`invert_segment`).
    fn invert_segment(t: f64, width: f64, v0: f64, v1: f64) -> f64 {
        t * (v0 + (v1 - v0) * 0.5 * t) * width
    }

    /// The point of `[0, 1]²` that a uniform `sample` maps to, with the density there.
    pub fn sample(&self, sample: [f64; 2], param: f64) -> ([f64; 2], f64) {
        let wt = weights(&self.params, param);
        let eps = f32::EPSILON as f64 * 0.5;
        let [mut sx, mut sy] = sample.map(|s| s.clamp(eps, 1.0 - eps));
        let row = (0..self.h - 1).find(|&r| self.marg_at(r, wt) >= sy).unwrap_or(self.h - 2);
        if row > 0 {
            sy -= self.marg_at(row - 1, wt);
        }
        let (r0, r1) = (self.cond_at(row, self.w - 2, wt), self.cond_at(row + 1, self.w - 2, wt));
        let fy = Self::sample_segment(sy, (self.h - 1) as f64, r0, r1);
        sx *= r0 + (r1 - r0) * fy;
        let cond = |c: usize| {
            let (a, b) = (self.cond_at(row, c, wt), self.cond_at(row + 1, c, wt));
            a + (b - a) * fy
        };
        let col = (0..self.w - 1).find(|&c| cond(c) >= sx).unwrap_or(self.w - 2);
        if col > 0 {
            sx -= cond(col - 1);
        }
        let lerp_y = |x: usize| {
            let (a, b) = (self.data_at(x, row, wt), self.data_at(x, row + 1, wt));
            a + (b - a) * fy
        };
        let (c0, c1) = (lerp_y(col), lerp_y(col + 1));
        let fx = Self::sample_segment(sx, (self.w - 1) as f64, c0, c1);
        (
            [(col as f64 + fx) / (self.w - 1) as f64, (row as f64 + fy) / (self.h - 1) as f64],
            c0 + (c1 - c0) * fx,
        )
    }

    /// The uniform sample that maps to `point` (the inverse of [`sample`](Self::sample)), with the density there.
    pub fn invert(&self, point: [f64; 2], param: f64) -> ([f64; 2], f64) {
        let wt = weights(&self.params, param);
        let (col, row, fx, fy) = patch(point, self.w, self.h);
        let lerp_y = |x: usize| {
            let (a, b) = (self.data_at(x, row, wt), self.data_at(x, row + 1, wt));
            a + (b - a) * fy
        };
        let (c0, c1) = (lerp_y(col), lerp_y(col + 1));
        let pdf = c0 + (c1 - c0) * fx;
        let mut sx = Self::invert_segment(fx, 1.0 / (self.w - 1) as f64, c0, c1);
        if col > 0 {
            let (a, b) = (self.cond_at(row, col - 1, wt), self.cond_at(row + 1, col - 1, wt));
            sx += a + (b - a) * fy;
        }
        let (r0, r1) = (self.cond_at(row, self.w - 2, wt), self.cond_at(row + 1, self.w - 2, wt));
        sx /= r0 + (r1 - r0) * fy;
        let mut sy = Self::invert_segment(fy, 1.0 / (self.h - 1) as f64, r0, r1);
        if row > 0 {
            sy += self.marg_at(row - 1, wt);
        }
        ([sx, sy], pdf)
    }
}

/// A grid of values on `[0, 1]²` read back by bilinear interpolation, per
/// slice of a parameter axis and linearly between slices (the plugin's
/// `ndf`, `sigma` and `spectra`, built with `normalize = false`).
#[derive(Debug, Clone)]
pub struct Grid {
    pub w: usize,
    pub h: usize,
    pub params: Vec<f64>,
    pub values: Vec<f32>,
}

impl Grid {
    pub fn eval(&self, point: [f64; 2], param: f64) -> f64 {
        let wt = weights(&self.params, param);
        let (col, row, fx, fy) = patch(point, self.w, self.h);
        let at = |x: usize, y: usize| {
            let i = y * self.w + x;
            let n = self.w * self.h;
            let v0 = self.values[wt.slice * n + i] as f64 * wt.w0;
            if wt.w1 == 0.0 {
                v0
            } else {
                v0 + self.values[(wt.slice + 1) * n + i] as f64 * wt.w1
            }
        };
        let c0 = at(col, row) + (at(col, row + 1) - at(col, row)) * fy;
        let c1 = at(col + 1, row) + (at(col + 1, row + 1) - at(col + 1, row)) * fy;
        c0 + (c1 - c0) * fx
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bumpy(w: usize, h: usize, shift: f64) -> Vec<f32> {
        let mut v = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let (u, t) = (x as f64 / (w - 1) as f64, y as f64 / (h - 1) as f64);
                v.push((0.1 + (-((u - shift).powi(2) + (t - 0.5).powi(2)) / 0.01).exp()) as f32);
            }
        }
        v
    }

    #[test]
    fn invert_undoes_sample_and_the_density_integrates_to_one() {
        let (w, h) = (9, 7);
        let mut values = bumpy(w, h, 0.3);
        values.extend(bumpy(w, h, 0.6));
        let m = Marginal::new(&values, w, h, &[0.0, 1.0]);
        for &p in &[0.0, 0.4, 1.0] {
            let mut total = 0.0;
            let n = 200;
            for i in 0..n {
                for j in 0..n {
                    let s = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                    let (pt, pdf) = m.sample(s, p);
                    let (back, pdf_back) = m.invert(pt, p);
                    // The plugin takes a segment whose ends differ by less than 1e-4 as
                    // flat, which its inverse undoes only to about 1e-5.
                    assert!(
                        (back[0] - s[0]).abs() < 1e-5 && (back[1] - s[1]).abs() < 1e-5,
                        "{s:?} → {pt:?} → {back:?}"
                    );
                    assert!((pdf - pdf_back).abs() < 1e-9 * pdf);
                    let e = m.invert(s, p).1;
                    total += e / (n * n) as f64;
                }
            }
            assert!((total - 1.0).abs() < 1e-3, "∫ = {total}");
        }
    }

    #[test]
    fn a_grid_interpolates_between_nodes_and_slices() {
        let g = Grid {
            w: 2,
            h: 2,
            params: vec![0.0, 2.0],
            values: vec![0.0, 1.0, 2.0, 3.0, 10.0, 11.0, 12.0, 13.0],
        };
        assert!((g.eval([0.5, 0.5], 0.0) - 1.5).abs() < 1e-12);
        assert!((g.eval([1.0, 0.0], 1.0) - 6.0).abs() < 1e-12);
        assert!((g.eval([0.0, 1.0], 5.0) - 12.0).abs() < 1e-12);
    }
}
