//! Learning the detection chain on a strong, steady signal: the mean
//! chop-period waveform (with the offset drift removed), its phase against
//! the square and sine references, and the matched reference built from it.

use super::learned::{Learned, MAX_M};
use super::nuisance::Nuisance;
use super::reference::Reference;
use gonio_shared::Reference as Kind;

/// Accumulates periods to learn from.
pub struct Learner {
    m: usize,
    sums: [i64; MAX_M],
    periods: u32,
    nuisance: Nuisance,
}

impl Learner {
    pub fn new(m: usize, planned: u32, chop_hz: f64) -> Self {
        Learner {
            m: m.clamp(4, MAX_M),
            sums: [0; MAX_M],
            periods: 0,
            nuisance: Nuisance::new(planned, chop_hz),
        }
    }

    pub fn push(&mut self, codes: &[u16]) {
        let mut total = 0i64;
        for (s, &c) in self.sums[..self.m].iter_mut().zip(codes) {
            *s += c as i64;
            total += c as i64;
        }
        self.nuisance.push(total as f64, 0.0);
        self.periods += 1;
    }

    /// The learned waveform and phases; `None` before any period.
    pub fn finish(&self) -> Option<Learned> {
        if self.periods == 0 {
            return None;
        }
        let (m, n) = (self.m, self.periods as f64);
        let drift = self.nuisance.sum_slope_per_period() / (m * m) as f64;
        let mut w = [0.0f64; MAX_M];
        for (k, (x, &s)) in w.iter_mut().zip(&self.sums[..m]).enumerate() {
            *x = s as f64 / n - drift * k as f64;
        }
        let mean = w[..m].iter().sum::<f64>() / m as f64;
        w[..m].iter_mut().for_each(|x| *x -= mean);
        let phase = |kind| {
            let (i, q) = Reference::new(kind, m, None).correlate(&w[..m]);
            libm::atan2(q, i)
        };
        Some(Learned {
            m,
            waveform: w,
            phase_square: phase(Kind::Square),
            phase_sine: phase(Kind::Sine),
        })
    }
}
