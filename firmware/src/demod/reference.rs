//! Reference waveforms over one chop period, and the per-period correlation
//! (the only code that touches every sample).

use super::learned::{Learned, MAX_M};
use gonio_shared::Reference as Kind;

/// Scale of sine and matched tables (Q14).
const FULL: f64 = 16383.0;

/// One reference: integers that sum to exactly zero over the period.
#[derive(Clone)]
pub struct Table {
    v: [i16; MAX_M],
    m: usize,
}

impl Table {
    /// Rounds `f(k)` (already scaled) and spreads the rounding residue so the
    /// table sums to zero.
    fn from_fn(m: usize, f: impl Fn(usize) -> f64) -> Self {
        let mut t = Table { v: [0; MAX_M], m };
        for k in 0..m {
            t.v[k] = libm::round(f(k)).clamp(-FULL, FULL) as i16;
        }
        let mut residue: i64 = t.values().iter().map(|&x| x as i64).sum();
        let mut k = 0;
        while residue != 0 {
            let step = residue.signum() as i16;
            let x = t.v[k].saturating_sub(step);
            if x.unsigned_abs() <= FULL as u16 {
                t.v[k] = x;
                residue -= step as i64;
            }
            k = (k + 1) % m;
        }
        t
    }

    pub fn values(&self) -> &[i16] {
        &self.v[..self.m]
    }

    /// `Σ k·r_k`: the response of this reference to a unit-slope ramp. Summed
    /// in integers (exact: |Σ| < 2^32) and converted once.
    pub fn ramp_moment(&self) -> f64 {
        self.values().iter().enumerate().map(|(k, &r)| k as i64 * r as i64).sum::<i64>() as f64
    }

    /// `Σ r_k·w_k` for a waveform in codes.
    pub fn dot(&self, w: &[f64]) -> f64 {
        self.values().iter().zip(w).map(|(&r, &x)| r as f64 * x).sum()
    }
}

/// The correlation sums of one chop period.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Period {
    pub i: i64,
    pub q: i64,
    /// Against the matched reference (zero when none is selected).
    pub matched: i64,
    /// Sum of the codes, for the drift fit.
    pub sum: i64,
    pub min: u16,
    pub max: u16,
}

/// The references of a measurement and how their sums become amplitudes.
#[derive(Clone)]
pub struct Reference {
    kind: Kind,
    i: Table,
    q: Table,
    matched: Option<Table>,
    /// In-phase sum of a unit chop (1 during the first half-period): divides
    /// I and Q into chop amplitudes.
    unit_i: f64,
    /// Matched sum per unit of (boxcar-equivalent) chop amplitude.
    unit_matched: f64,
    /// Learned phase of the electronics for this reference kind, as its
    /// cosine and sine: every period's amplitude projects on it, and `libm`'s
    /// f64 cosine and sine cost thousands of instructions each on the chip.
    phase_ref: (f64, f64),
}

impl Reference {
    /// `m` must be a multiple of 4 and ≤ [`MAX_M`] (the settings validation
    /// checks it); other values are clamped so nothing here can panic. The
    /// matched kind needs `learned` for the same M; without it the in-phase
    /// square is used instead.
    pub fn new(kind: Kind, m: usize, learned: Option<&Learned>) -> Self {
        let m = (m.clamp(4, MAX_M) / 4) * 4;
        let (i, q) = match kind {
            Kind::Sine => {
                let ph = |k: usize| 2.0 * core::f64::consts::PI * (k as f64 + 0.5) / m as f64;
                (
                    Table::from_fn(m, |k| FULL * libm::sin(ph(k))),
                    Table::from_fn(m, |k| -FULL * libm::cos(ph(k))),
                )
            }
            // The matched kind reports I and Q against the square.
            Kind::Square | Kind::Matched => (
                Table::from_fn(m, |k| if k < m / 2 { 1.0 } else { -1.0 }),
                // Quadrature: the in-phase square delayed by a quarter period.
                Table::from_fn(m, |k| if (m / 4..3 * m / 4).contains(&k) { 1.0 } else { -1.0 }),
            ),
        };
        let unit_i = i.values()[..m / 2].iter().map(|&v| v as f64).sum();
        let learned = learned.filter(|l| l.samples_per_period() == m);
        let phase = learned.map_or(0.0, |l| match kind {
            Kind::Sine => l.phase_sine,
            Kind::Square | Kind::Matched => l.phase_square,
        });
        let phase_ref = (libm::cos(phase), libm::sin(phase));
        let mut r = Reference {
            kind,
            i,
            q,
            matched: None,
            unit_i,
            unit_matched: 1.0,
            phase_ref,
        };
        if let (Kind::Matched, Some(l)) = (kind, learned) {
            let w = l.waveform();
            let peak = w.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1e-12);
            let t = Table::from_fn(m, |k| FULL * w[k] / peak);
            // Scale: the matched amplitude of the learned waveform equals
            // its phase-projected square amplitude.
            let boxcar = r.project(r.i.dot(w), r.q.dot(w));
            if boxcar.abs() > 0.0 {
                r.unit_matched = t.dot(w) / boxcar;
                r.matched = Some(t);
            }
        }
        r
    }

    pub fn samples_per_period(&self) -> usize {
        self.i.m
    }

    /// True when the matched waveform is in use.
    pub fn is_matched(&self) -> bool {
        self.matched.is_some()
    }

    pub fn kind(&self) -> Kind {
        self.kind
    }

    /// In-phase and quadrature sums → chop amplitude along the reference phase.
    pub fn project(&self, i: f64, q: f64) -> f64 {
        (self.phase_ref.0 * i + self.phase_ref.1 * q) / self.unit_i
    }

    /// Per-period amplitude (chop amplitude in codes) from a period's sums.
    pub fn amplitude(&self, p: &Period) -> f64 {
        match &self.matched {
            Some(_) => p.matched as f64 / self.unit_matched,
            None => self.project(p.i as f64, p.q as f64),
        }
    }

    /// What a unit drift slope (one code per sample) adds to a period's amplitude.
    pub fn drift_response(&self) -> f64 {
        match &self.matched {
            Some(t) => t.ramp_moment() / self.unit_matched,
            None => self.project(self.i.ramp_moment(), self.q.ramp_moment()),
        }
    }

    /// Drift responses of the in-phase and quadrature sums (unit slope).
    pub fn drift_iq(&self) -> (f64, f64) {
        (self.i.ramp_moment(), self.q.ramp_moment())
    }

    /// In-phase and quadrature sums of a waveform (codes, one period).
    pub fn correlate(&self, w: &[f64]) -> (f64, f64) {
        (self.i.dot(w), self.q.dot(w))
    }

    pub fn unit_i(&self) -> f64 {
        self.unit_i
    }

    /// Correlates one period of codes (`codes.len()` should be M; extra codes
    /// are ignored, missing ones count as zero).
    #[inline]
    pub fn period(&self, codes: &[u16]) -> Period {
        let (mut i, mut q, mut mt, mut sum) = (0i64, 0i64, 0i64, 0i64);
        let (mut min, mut max) = (u16::MAX, 0u16);
        let (ti, tq) = (self.i.values(), self.q.values());
        match &self.matched {
            Some(t) => {
                for (((&c, &ri), &rq), &rm) in codes.iter().zip(ti).zip(tq).zip(t.values()) {
                    let x = c as i64;
                    i += x * ri as i64;
                    q += x * rq as i64;
                    mt += x * rm as i64;
                    sum += x;
                    min = min.min(c);
                    max = max.max(c);
                }
            }
            None => {
                for ((&c, &ri), &rq) in codes.iter().zip(ti).zip(tq) {
                    let x = c as i64;
                    i += x * ri as i64;
                    q += x * rq as i64;
                    sum += x;
                    min = min.min(c);
                    max = max.max(c);
                }
            }
        }
        Period {
            i,
            q,
            matched: mt,
            sum,
            min,
            max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_sum_to_zero_and_stay_in_range() {
        for m in [4, 8, 12, 60, 64, 100, 512] {
            for kind in [Kind::Square, Kind::Sine] {
                let r = Reference::new(kind, m, None);
                assert_eq!(r.i.values().iter().map(|&v| v as i64).sum::<i64>(), 0);
                assert_eq!(r.q.values().iter().map(|&v| v as i64).sum::<i64>(), 0);
            }
        }
        let t = Table::from_fn(7, |k| FULL * (k as f64 - 2.9) / 4.1);
        assert_eq!(t.values().iter().map(|&v| v as i64).sum::<i64>(), 0);
        assert!(t.values().iter().all(|v| v.unsigned_abs() <= FULL as u16));
    }
}
