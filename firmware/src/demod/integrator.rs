//! One integration: correlation sums over whole chop periods, the nuisance
//! fit, and the drift-corrected estimate.

use super::nuisance::{Design, Nuisance};
use super::reference::{Period, Reference};

/// The result of an integration, in ADC codes of chop amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// In-phase and quadrature chop amplitudes (square or sine reference).
    pub i: f64,
    pub q: f64,
    /// Amplitude along the reference phase, or against the matched waveform.
    pub amplitude: f64,
    /// `√(i² + q²)`.
    pub magnitude: f64,
    /// Standard error of `amplitude`, from the per-period spread with the
    /// mains terms fitted out.
    pub std_err: f64,
    /// Phase of (i, q) in degrees.
    pub phase_deg: f64,
    /// Offset drift found and removed (codes per sample).
    pub drift: f64,
    pub periods: u32,
    pub min: u16,
    pub max: u16,
}

pub struct Integrator<'r> {
    r: &'r Reference,
    nuisance: Nuisance,
    sum_i: i64,
    sum_q: i64,
    periods: u32,
    min: u16,
    max: u16,
}

impl<'r> Integrator<'r> {
    /// For `planned` periods at `chop_hz` (the fit of mains aliases needs both).
    pub fn new(r: &'r Reference, planned: u32, chop_hz: f64) -> Self {
        Self::with(r, Design::new(planned, chop_hz))
    }

    /// On the regression's design for its planned periods, computed before
    /// (see [`Design`]: the measurement then pays only for its data).
    pub fn with(r: &'r Reference, design: Design) -> Self {
        Integrator {
            r,
            nuisance: Nuisance::with(design),
            sum_i: 0,
            sum_q: 0,
            periods: 0,
            min: u16::MAX,
            max: 0,
        }
    }

    /// Adds one chop period of codes.
    pub fn push(&mut self, codes: &[u16]) -> Period {
        let p = self.r.period(codes);
        self.sum_i += p.i;
        self.sum_q += p.q;
        self.min = self.min.min(p.min);
        self.max = self.max.max(p.max);
        self.nuisance.push(p.sum as f64, self.r.amplitude(&p));
        self.periods += 1;
        p
    }

    pub fn estimate(&self) -> Estimate {
        self.estimate_with(self.drift())
    }

    /// The offset's drift (codes per sample), from the fit of the period
    /// sums: the first of the two fits [`Integrator::estimate`] makes, each
    /// some 150 000 instructions on the chip (soft-float f64), so a caller
    /// can yield between them.
    pub fn drift(&self) -> f64 {
        let m = self.r.samples_per_period() as f64;
        // A drift of d codes per sample raises each period's code sum by d·M²
        // per period and biases every correlation sum by d·Σk·r_k.
        self.nuisance.sum_slope_per_period() / (m * m)
    }

    /// The estimate, given the [`Integrator::drift`].
    pub fn estimate_with(&self, drift: f64) -> Estimate {
        let n = self.periods.max(1) as f64;
        let (di, dq) = self.r.drift_iq();
        let unit = self.r.unit_i();
        let i = (self.sum_i as f64 / n - drift * di) / unit;
        let q = (self.sum_q as f64 / n - drift * dq) / unit;
        let (a, std_err) = self.nuisance.amplitude();
        Estimate {
            i,
            q,
            amplitude: a - drift * self.r.drift_response(),
            magnitude: libm::sqrt(i * i + q * q),
            std_err,
            phase_deg: libm::atan2(q, i).to_degrees(),
            drift,
            periods: self.periods,
            min: self.min,
            max: self.max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::learned::MAX_M;
    use super::*;
    use gonio_shared::Reference as Kind;

    fn chop(m: usize, amp: f64, base: f64, delay: usize) -> impl Fn(usize) -> f64 {
        move |k| base + if ((k + m - delay) % m) < m / 2 { amp } else { 0.0 }
    }

    fn codes(f: &dyn Fn(usize) -> f64, p: usize, m: usize, out: &mut [u16]) {
        for (k, o) in out[..m].iter_mut().enumerate() {
            *o = libm::round(f(p * m + k)) as u16;
        }
    }

    #[test]
    fn recovers_amplitude_and_rejects_dc_with_every_reference() {
        for kind in [Kind::Square, Kind::Sine] {
            let r = Reference::new(kind, 64, None);
            let mut it = Integrator::new(&r, 23, 230.0);
            let f = chop(64, 1000.0, 777.0, 0);
            let mut buf = [0u16; MAX_M];
            for p in 0..23 {
                codes(&|k| f(k % 64), p, 64, &mut buf);
                it.push(&buf[..64]);
            }
            let e = it.estimate();
            assert!((e.amplitude - 1000.0).abs() < 1e-6, "{kind:?}: {e:?}");
            assert!(e.std_err < 1e-6 && e.phase_deg.abs() < 1e-6 && e.drift.abs() < 1e-9);
        }
    }

    #[test]
    fn removes_a_linear_drift_exactly() {
        let r = Reference::new(Kind::Square, 64, None);
        let mut it = Integrator::new(&r, 23, 230.0);
        let mut buf = [0u16; MAX_M];
        // 1000-code chop on an offset rising 2000 codes across the window.
        let slope = 2000.0 / (23.0 * 64.0);
        for p in 0..23 {
            for (k, b) in buf[..64].iter_mut().enumerate() {
                let t = (p * 64 + k) as f64;
                *b = libm::round(500.0 + slope * t + if k < 32 { 1000.0 } else { 0.0 }) as u16;
            }
            it.push(&buf[..64]);
        }
        let e = it.estimate();
        assert!((e.drift - slope).abs() < 1e-3 * slope, "{e:?}");
        assert!((e.amplitude - 1000.0).abs() < 0.05, "{e:?}");
    }

    #[test]
    fn a_quarter_period_delay_is_ninety_degrees() {
        let r = Reference::new(Kind::Sine, 64, None);
        let mut it = Integrator::new(&r, 4, 230.0);
        let f = chop(64, 1000.0, 0.0, 16);
        let mut buf = [0u16; MAX_M];
        for p in 0..4 {
            codes(&|k| f(k % 64), p, 64, &mut buf);
            it.push(&buf[..64]);
        }
        let e = it.estimate();
        assert!((e.phase_deg - 90.0).abs() < 0.5, "{e:?}");
        assert!((e.magnitude - 1000.0).abs() < 5.0, "{e:?}");
    }

    #[test]
    fn worst_case_sums_do_not_overflow() {
        // Full-scale codes against the Q14 sine over 10 s at the largest M.
        let r = Reference::new(Kind::Sine, MAX_M, None);
        let buf: [u16; MAX_M] = core::array::from_fn(|k| if k < MAX_M / 2 { 4095 } else { 0 });
        let mut it = Integrator::new(&r, 50_000, 5000.0);
        for _ in 0..50_000 {
            it.push(&buf);
        }
        let e = it.estimate();
        assert!((e.amplitude - 4095.0).abs() < 1e-6, "{e:?}");
    }
}
