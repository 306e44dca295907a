//! Synchronous demodulation in integers, one chop period at a time.
//!
//! Each period of M codes is multiplied by an in-phase and a quadrature
//! reference (±1 square, or a Q14 sine table) and summed; per-period sums are
//! accumulated with their squares so the amplitude's standard error comes from
//! their spread. Integrating whole chop periods over a window that is also a
//! whole number of mains periods (23 periods at 230 Hz = 100 ms) nulls 50 and
//! 60 Hz pickup and the DC of ambient light.
//!
//! Ranges: a code is < 2^12, a reference value ≤ 2^14, M ≤ 512, so one period's
//! sum is < 2^35 (i64), a 10 s integration of 5 kHz chop periods stays < 2^51,
//! and the sums of squares (< 2^70 per period) are kept in i128.

use gonio_shared::Reference as RefKind;

/// Largest supported samples per period (`DetectionSettings::SAMPLES_PER_PERIOD_MAX`).
pub const MAX_M: usize = 512;
const Q14: f64 = 16384.0;

/// Reference waveforms for one chop period.
#[derive(Clone)]
pub struct Reference {
    m: usize,
    i: [i16; MAX_M],
    q: [i16; MAX_M],
    /// `Σ u_k r_k` for the unit on/off waveform `u` (1 while the laser is on,
    /// the first half-period): the in-phase sum of a chop of amplitude one code.
    norm: i64,
}

impl Reference {
    /// `m` must be a multiple of 4 and ≤ [`MAX_M`] (checked by the settings
    /// validation); other values are clamped so nothing here can panic.
    pub fn new(kind: RefKind, m: usize) -> Self {
        let m = (m.clamp(4, MAX_M) / 4) * 4;
        let mut r = Reference {
            m,
            i: [0; MAX_M],
            q: [0; MAX_M],
            norm: 0,
        };
        for k in 0..m {
            let (vi, vq) = match kind {
                RefKind::Square => {
                    let i = if k < m / 2 { 1 } else { -1 };
                    // Quadrature: the in-phase square delayed by a quarter period.
                    let q = if (m / 4..3 * m / 4).contains(&k) { 1 } else { -1 };
                    (i, q)
                }
                RefKind::Sine => {
                    let ph = 2.0 * core::f64::consts::PI * (k as f64 + 0.5) / m as f64;
                    (libm::round(Q14 * libm::sin(ph)) as i16, libm::round(-Q14 * libm::cos(ph)) as i16)
                }
            };
            r.i[k] = vi;
            r.q[k] = vq;
        }
        r.norm = r.i[..m / 2].iter().map(|&v| v as i64).sum();
        r
    }

    pub fn samples_per_period(&self) -> usize {
        self.m
    }
}

/// The demodulated sums of one chop period, and its code extremes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Period {
    pub i: i64,
    pub q: i64,
    pub min: u16,
    pub max: u16,
}

/// Demodulates one period (`codes.len()` must equal the reference's M; extra
/// codes are ignored, missing ones count as zero).
pub fn demod_period(r: &Reference, codes: &[u16]) -> Period {
    let (mut i, mut q) = (0i64, 0i64);
    let (mut min, mut max) = (u16::MAX, 0u16);
    for ((&c, &ri), &rq) in codes.iter().zip(&r.i[..r.m]).zip(&r.q[..r.m]) {
        i += c as i64 * ri as i64;
        q += c as i64 * rq as i64;
        min = min.min(c);
        max = max.max(c);
    }
    Period { i, q, min, max }
}

/// Sums over the periods of one integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Accumulator {
    pub periods: u32,
    sum_i: i64,
    sum_q: i64,
    sum_ii: i128,
    sum_qq: i128,
    sum_iq: i128,
    pub min: u16,
    pub max: u16,
}

/// The result of an integration, in ADC codes of chop amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    pub i: f64,
    pub q: f64,
    /// Amplitude projected on the reference phase.
    pub amplitude: f64,
    /// Standard error of `amplitude` from the per-period spread.
    pub std_err: f64,
    /// Phase of (i, q) in degrees.
    pub phase_deg: f64,
    pub periods: u32,
}

impl Accumulator {
    pub fn new() -> Self {
        Self {
            min: u16::MAX,
            ..Default::default()
        }
    }

    pub fn push(&mut self, p: Period) {
        self.periods += 1;
        self.sum_i += p.i;
        self.sum_q += p.q;
        self.sum_ii += p.i as i128 * p.i as i128;
        self.sum_qq += p.q as i128 * p.q as i128;
        self.sum_iq += p.i as i128 * p.q as i128;
        self.min = self.min.min(p.min);
        self.max = self.max.max(p.max);
    }

    /// Amplitude, phase and standard error, with the amplitude projected on
    /// `phase_ref_deg` (the calibrated delay of the electronics).
    pub fn estimate(&self, r: &Reference, phase_ref_deg: f64) -> Estimate {
        let n = self.periods.max(1) as f64;
        let norm = r.norm.max(1) as f64;
        let (mi, mq) = (self.sum_i as f64 / n, self.sum_q as f64 / n);
        let (c, s) = (libm::cos(phase_ref_deg.to_radians()), libm::sin(phase_ref_deg.to_radians()));
        // Sample (co)variances of the per-period sums.
        let var = |sxx: i128, sx: i64, sy: i64| -> f64 {
            if self.periods < 2 {
                return 0.0;
            }
            let (sx, sy) = (sx as f64, sy as f64);
            ((sxx as f64 - sx * sy / n) / (n - 1.0)).max(0.0)
        };
        let (vii, vqq) = (var(self.sum_ii, self.sum_i, self.sum_i), var(self.sum_qq, self.sum_q, self.sum_q));
        let viq = if self.periods < 2 {
            0.0
        } else {
            (self.sum_iq as f64 - self.sum_i as f64 * self.sum_q as f64 / n) / (n - 1.0)
        };
        let var_a = (c * c * vii + s * s * vqq + 2.0 * c * s * viq).max(0.0);
        Estimate {
            i: mi / norm,
            q: mq / norm,
            amplitude: (c * mi + s * mq) / norm,
            std_err: libm::sqrt(var_a / n) / norm,
            phase_deg: libm::atan2(mq, mi).to_degrees(),
            periods: self.periods,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chop(m: usize, amp: u16, base: u16, delay: usize) -> [u16; MAX_M] {
        let mut out = [0u16; MAX_M];
        for (k, o) in out[..m].iter_mut().enumerate() {
            let on = ((k + m - delay) % m) < m / 2;
            *o = base + if on { amp } else { 0 };
        }
        out
    }

    #[test]
    fn square_recovers_amplitude_and_rejects_dc() {
        for kind in [RefKind::Square, RefKind::Sine] {
            let r = Reference::new(kind, 64);
            let codes = chop(64, 1000, 777, 0);
            let mut acc = Accumulator::new();
            for _ in 0..23 {
                acc.push(demod_period(&r, &codes[..64]));
            }
            let e = acc.estimate(&r, 0.0);
            assert!((e.amplitude - 1000.0).abs() < 1e-9, "{kind:?}: {e:?}");
            assert_eq!(e.std_err, 0.0);
            assert!(e.phase_deg.abs() < 1e-9);
        }
    }

    #[test]
    fn delayed_signal_shows_phase_and_projects_back() {
        let r = Reference::new(RefKind::Sine, 64);
        // A quarter-period delay (16 samples) is 90°.
        let codes = chop(64, 1000, 0, 16);
        let mut acc = Accumulator::new();
        acc.push(demod_period(&r, &codes[..64]));
        let e = acc.estimate(&r, 90.0);
        assert!((e.phase_deg - 90.0).abs() < 0.5, "{e:?}");
        assert!((e.amplitude - 1000.0).abs() < 5.0, "{e:?}");
    }

    #[test]
    fn worst_case_sums_do_not_overflow() {
        // Full-scale codes against the Q14 sine over 10 s at the largest M.
        let r = Reference::new(RefKind::Sine, MAX_M);
        let codes = chop(MAX_M, 4095, 0, 0);
        let p = demod_period(&r, &codes[..MAX_M]);
        let mut acc = Accumulator::new();
        for _ in 0..50_000 {
            acc.push(p);
        }
        let e = acc.estimate(&r, 0.0);
        assert!((e.amplitude - 4095.0).abs() < 1e-6, "{e:?}");
    }
}
