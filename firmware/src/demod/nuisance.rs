//! The slow part of the signal, seen one value per chop period: a constant, a
//! linear drift, and mains pickup (50 and 60 Hz with their second and third
//! harmonics) as it aliases at the chop rate. Per-period values are regressed
//! on these by least squares: the right-hand sides are accumulated period by
//! period; the Gram matrix, which does not depend on the data, is factored
//! once per settings ([`Design`]).
//!
//! The normal equations are solved by a Cholesky factorisation written here:
//! at most 14 unknowns, fixed size, no heap, no_std; a linear-algebra crate
//! would bring generic machinery and code size to the chip for 30 lines.

/// Mains frequencies fitted (Hz): 50 and 60 Hz and their 2nd and 3rd harmonics.
const MAINS_HZ: [f64; 6] = [50.0, 100.0, 150.0, 60.0, 120.0, 180.0];
const MAX_TONES: usize = MAINS_HZ.len();
/// Constant, ramp, and a sine and cosine per tone.
pub const MAX_REG: usize = 2 + 2 * MAX_TONES;
/// Column of the ramp regressor.
const RAMP: usize = 1;

type Mat = [[f64; MAX_REG]; MAX_REG];

/// The regressors' column lists: all of them (the slope fit), and all but
/// the ramp (the amplitude fit: a drift biases all periods alike).
#[derive(Clone, Copy)]
struct Columns {
    idx: [usize; MAX_REG],
    len: usize,
}

impl Columns {
    fn all(n: usize) -> Self {
        Columns {
            idx: core::array::from_fn(|i| i),
            len: n,
        }
    }

    fn without_ramp(n: usize) -> Self {
        let mut idx = [0usize; MAX_REG];
        for (j, slot) in idx[1..n - 1].iter_mut().enumerate() {
            *slot = j + 2;
        }
        Columns { idx, len: n - 1 }
    }

    fn as_slice(&self) -> &[usize] {
        &self.idx[..self.len]
    }
}

/// What the regression depends on but not the data: the tones that alias
/// clear of DC and of each other at the chop rate, and, for the planned
/// number of periods, the Cholesky factors of the two Gram matrices. The
/// regressors are the same in every measurement with the same settings, so
/// the factors are computed once (`Detector` keeps the design of its
/// settings): measured on the Cortex-M4 (`chip-bench`), accumulating the Gram
/// matrix cost some 20 000 instructions a period and each factorisation
/// about 150 000 at the end of every measurement, in soft-float f64.
#[derive(Clone)]
pub struct Design {
    n: usize,
    tones: usize,
    planned: u32,
    /// Per-period rotation (cos, sin) of each tone.
    step: [(f64, f64); MAX_TONES],
    /// Factors of the Gram matrix of `planned` periods, for all regressors
    /// and for all but the ramp (`None`: not positive definite), when
    /// `factored`.
    full: Option<Factor>,
    amp: Option<Factor>,
    factored: bool,
}

/// Longest integration (periods) whose Gram matrix is factored up front, in
/// one stretch at configure: 657 000 instructions for 23 periods, 8.7 M
/// (52 ms) for 256 on the chip (`chip-bench`'s `design_instructions`); a
/// longer integration (up to 50 000 periods, seconds of work at once, past
/// the watchdog) accumulates its own Gram matrix over its periods, at about
/// five times a factored design's cost per period (`chip-bench`).
const PRECOMPUTE_MAX_PERIODS: u32 = 256;

impl Design {
    /// For `planned` periods at `chop_hz`, factored ([`Design::precompute`]).
    pub fn new(planned: u32, chop_hz: f64) -> Self {
        let mut d = Self::unfactored(planned, chop_hz);
        d.precompute();
        d
    }

    /// For `planned` periods at `chop_hz`, its factors still to compute: an
    /// integration on it accumulates its own Gram matrix meanwhile. Tones
    /// that alias to (nearly) DC or Nyquist, or onto another tone, are
    /// skipped, as are all tones when the integration is too short to fit
    /// them.
    pub fn unfactored(planned: u32, chop_hz: f64) -> Self {
        let k = planned.max(1) as f64;
        let half_bin = chop_hz / (2.0 * k);
        let mut freqs = [0.0f64; MAX_TONES];
        let mut tones = 0;
        for f in MAINS_HZ {
            let folded = libm::fabs(f - chop_hz * libm::round(f / chop_hz));
            let clear = folded > 2.0 * half_bin && folded < chop_hz / 2.0 - half_bin;
            let new = freqs[..tones].iter().all(|g| libm::fabs(g - folded) > half_bin);
            // Keep at least three spare degrees of freedom for the residual.
            if clear && new && (2 + 2 * (tones + 1) + 3) as f64 <= k {
                freqs[tones] = folded;
                tones += 1;
            }
        }
        let mut step = [(1.0, 0.0); MAX_TONES];
        for (s, f) in step.iter_mut().zip(&freqs[..tones]) {
            let w = 2.0 * core::f64::consts::PI * f / chop_hz;
            *s = (libm::cos(w), libm::sin(w));
        }
        Design {
            n: 2 + 2 * tones,
            tones,
            planned: planned.max(1),
            step,
            full: None,
            amp: None,
            factored: false,
        }
    }

    /// Factors the Gram matrices of the planned periods, in place, unless
    /// they are already or the integration is too long to factor up front.
    pub fn precompute(&mut self) {
        if self.factored || self.planned > PRECOMPUTE_MAX_PERIODS {
            return;
        }
        let gram = self.gram(self.planned);
        self.full = factor(&gram, Columns::all(self.n).as_slice());
        self.amp = (self.n > 2)
            .then(|| factor(&gram, Columns::without_ramp(self.n).as_slice()))
            .flatten();
        self.factored = true;
    }

    /// Periods the design is for.
    pub fn planned(&self) -> u32 {
        self.planned
    }

    /// The regressors of period `period`, the tones' phasors being `phasor`.
    fn regressors(&self, period: u32, phasor: &[(f64, f64); MAX_TONES]) -> [f64; MAX_REG] {
        let mut g = [0.0; MAX_REG];
        g[0] = 1.0;
        // Centred and scaled ramp keeps the Gram matrix well conditioned.
        g[RAMP] = (period as f64 - (self.planned as f64 - 1.0) / 2.0) / self.planned as f64;
        for t in 0..self.tones {
            g[2 + 2 * t] = phasor[t].1;
            g[3 + 2 * t] = phasor[t].0;
        }
        g
    }

    /// The tones' phasors one period on.
    fn rotate(&self, phasor: &mut [(f64, f64); MAX_TONES]) {
        for (p, &(dc, ds)) in phasor.iter_mut().zip(&self.step).take(self.tones) {
            let (c, s) = *p;
            *p = (c * dc - s * ds, s * dc + c * ds);
        }
    }

    /// The Gram matrix of the first `periods` periods.
    fn gram(&self, periods: u32) -> Mat {
        let mut gram = [[0.0; MAX_REG]; MAX_REG];
        let mut phasor = [(1.0, 0.0); MAX_TONES];
        for p in 0..periods {
            let g = self.regressors(p, &phasor);
            for r in 0..self.n {
                for c in 0..self.n {
                    gram[r][c] += g[r] * g[c];
                }
            }
            self.rotate(&mut phasor);
        }
        gram
    }

    /// The factor for `cols` after `periods` periods: the cached one for the
    /// planned count, else from the Gram matrix the integration accumulated,
    /// else computed (an integration cut short).
    fn factor(&self, periods: u32, cols: Columns, cached: &Option<Factor>, gram: Option<&Mat>) -> Option<Factor> {
        match gram {
            _ if self.factored && periods == self.planned => cached.clone(),
            Some(g) => factor(g, cols.as_slice()),
            None => factor(&self.gram(periods), cols.as_slice()),
        }
    }
}

/// Per-period regression of a code sum and of the amplitude on the slow terms.
pub struct Nuisance {
    design: Design,
    /// The Gram matrix, accumulated when the design has no factors.
    gram: Option<Mat>,
    periods: u32,
    /// The tones' current phasors.
    phasor: [(f64, f64); MAX_TONES],
    /// Right-hand sides: the code sum, and the amplitude minus its first value.
    b_sum: [f64; MAX_REG],
    b_amp: [f64; MAX_REG],
    amp0: Option<f64>,
    amp_sq: f64,
}

impl Nuisance {
    /// For `planned` periods at `chop_hz` (computes the [`Design`]).
    pub fn new(planned: u32, chop_hz: f64) -> Self {
        Self::with(Design::new(planned, chop_hz))
    }

    /// On a design computed before.
    pub fn with(design: Design) -> Self {
        Nuisance {
            gram: (!design.factored).then_some([[0.0; MAX_REG]; MAX_REG]),
            design,
            periods: 0,
            phasor: [(1.0, 0.0); MAX_TONES],
            b_sum: [0.0; MAX_REG],
            b_amp: [0.0; MAX_REG],
            amp0: None,
            amp_sq: 0.0,
        }
    }

    /// Adds one period: its code sum and its amplitude.
    pub fn push(&mut self, sum: f64, amplitude: f64) {
        let d = &self.design;
        let g = d.regressors(self.periods, &self.phasor);
        let a = amplitude - *self.amp0.get_or_insert(amplitude);
        if let Some(gram) = self.gram.as_mut() {
            for (row, gr) in gram.iter_mut().zip(g).take(d.n) {
                for (x, gc) in row.iter_mut().zip(g).take(d.n) {
                    *x += gr * gc;
                }
            }
        }
        for ((bs, ba), gr) in self.b_sum.iter_mut().zip(self.b_amp.iter_mut()).zip(g).take(d.n) {
            *bs += gr * sum;
            *ba += gr * a;
        }
        self.amp_sq += a * a;
        d.rotate(&mut self.phasor);
        self.periods += 1;
    }

    /// Drift of the code sum per period, or zero when the fit is not
    /// determined (too few periods).
    pub fn sum_slope_per_period(&self) -> f64 {
        let d = &self.design;
        if (self.periods as usize) < d.n + 2 {
            return 0.0;
        }
        match d.factor(self.periods, Columns::all(d.n), &d.full, self.gram.as_ref()) {
            Some(f) => f.solve(&self.b_sum)[RAMP] / d.planned as f64,
            None => 0.0,
        }
    }

    /// Mean amplitude with the mains terms fitted out, and its standard error
    /// from the residual spread; the plain mean and spread when there are too
    /// few periods for the fit.
    pub fn amplitude(&self) -> (f64, f64) {
        let d = &self.design;
        let n = self.periods as f64;
        let a0 = self.amp0.unwrap_or(0.0);
        let plain = || {
            let mean = self.b_amp[0] / n.max(1.0);
            let var = if n > 1.0 {
                ((self.amp_sq - n * mean * mean) / (n - 1.0)).max(0.0)
            } else {
                0.0
            };
            (a0 + mean, libm::sqrt(var / n.max(1.0)))
        };
        let m = d.n - 1;
        if m == 1 || (self.periods as usize) < m + 3 {
            return plain();
        }
        let cols = Columns::without_ramp(d.n);
        let b: [f64; MAX_REG] = core::array::from_fn(|j| if j < m { self.b_amp[cols.idx[j]] } else { 0.0 });
        match d.factor(self.periods, cols, &d.amp, self.gram.as_ref()) {
            Some(f) => {
                let x = f.solve(&b);
                let fitted: f64 = (0..m).map(|j| x[j] * b[j]).sum();
                let var = ((self.amp_sq - fitted) / (n - m as f64)).max(0.0);
                (a0 + x[0], libm::sqrt(var * f.inv00()))
            }
            None => plain(),
        }
    }
}

/// The Cholesky factor `L` of a Gram matrix restricted to some columns.
#[derive(Clone)]
struct Factor {
    l: Mat,
    n: usize,
}

/// Factors `G[idx,idx]`, or `None` when it is not positive definite.
fn factor(g: &Mat, idx: &[usize]) -> Option<Factor> {
    let n = idx.len();
    let mut l = [[0.0f64; MAX_REG]; MAX_REG];
    for r in 0..n {
        for c in 0..=r {
            let s: f64 = g[idx[r]][idx[c]] - (0..c).map(|k| l[r][k] * l[c][k]).sum::<f64>();
            if r == c {
                if s <= 1e-12 * g[idx[r]][idx[r]].max(1e-300) {
                    return None;
                }
                l[r][r] = libm::sqrt(s);
            } else {
                l[r][c] = s / l[c][c];
            }
        }
    }
    Some(Factor { l, n })
}

impl Factor {
    /// Solves `L·Lᵀ·x = rhs[..n]`.
    fn solve(&self, rhs: &[f64]) -> [f64; MAX_REG] {
        let (l, n) = (&self.l, self.n);
        let mut y = [0.0; MAX_REG];
        for r in 0..n {
            y[r] = (rhs[r] - (0..r).map(|k| l[r][k] * y[k]).sum::<f64>()) / l[r][r];
        }
        let mut x = [0.0; MAX_REG];
        for r in (0..n).rev() {
            x[r] = (y[r] - (r + 1..n).map(|k| l[k][r] * x[k]).sum::<f64>()) / l[r][r];
        }
        x
    }

    /// `(G⁻¹)₀₀`: the variance factor of the first unknown.
    fn inv00(&self) -> f64 {
        let mut e0 = [0.0; MAX_REG];
        e0[0] = 1.0;
        self.solve(&e0)[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_drift_slope_under_mains() {
        // Per-period sums: offset, slope 3 per period, 50 Hz alias (5 cycles
        // in 23 periods at 230 Hz) and a 150 Hz alias, no noise.
        let (k, fc) = (23u32, 230.0);
        let mut n = Nuisance::new(k, fc);
        for p in 0..k {
            let t = p as f64 / fc;
            let mains =
                900.0 * libm::sin(2.0 * core::f64::consts::PI * 50.0 * t + 0.3) + 90.0 * libm::cos(2.0 * core::f64::consts::PI * 150.0 * t);
            n.push(1000.0 + 3.0 * p as f64 + mains, 7.0 + 0.5 * mains);
        }
        assert!((n.sum_slope_per_period() - 3.0).abs() < 1e-9, "{}", n.sum_slope_per_period());
        let (a, se) = n.amplitude();
        assert!((a - 7.0).abs() < 1e-9 && se < 1e-6, "{a} {se}");
    }

    #[test]
    fn a_long_integration_accumulates_its_own_gram_matrix() {
        // Past the up-front limit the design has no factors: the integration
        // accumulates its Gram matrix and factors it, as a design would.
        let (k, fc) = (PRECOMPUTE_MAX_PERIODS + 1, 230.0);
        let design = Design::new(k, fc);
        assert!(!design.factored);
        let mut n = Nuisance::with(design);
        let mut reference = n.design.gram(0);
        let mut phasor = [(1.0, 0.0); MAX_TONES];
        for p in 0..k {
            let g = n.design.regressors(p, &phasor);
            n.design.rotate(&mut phasor);
            for r in 0..n.design.n {
                for c in 0..n.design.n {
                    reference[r][c] += g[r] * g[c];
                }
            }
            n.push(1000.0 + 3.0 * p as f64, 7.0);
        }
        assert_eq!(n.gram, Some(reference));
        assert!((n.sum_slope_per_period() - 3.0).abs() < 1e-9, "{}", n.sum_slope_per_period());
        let (a, se) = n.amplitude();
        assert!((a - 7.0).abs() < 1e-9 && se < 1e-6, "{a} {se}");
    }

    #[test]
    fn short_integrations_fall_back_to_the_plain_mean() {
        let mut n = Nuisance::new(2, 230.0);
        n.push(0.0, 1.0);
        n.push(0.0, 3.0);
        assert_eq!(n.sum_slope_per_period(), 0.0);
        let (a, se) = n.amplitude();
        assert_eq!(a, 2.0);
        assert!((se - 1.0).abs() < 1e-12);
    }
}
