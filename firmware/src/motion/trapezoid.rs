//! A rest-to-rest move of `n` steps under a speed limit `v` (steps/s) and an
//! acceleration limit `a` (steps/s²): constant acceleration, cruise, constant
//! deceleration (triangular when `n` is too short to reach `v`). Step k
//! (1-based) happens when the position reaches k.

/// The analytical profile, in seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trapezoid {
    pub n: u32,
    pub v: f64,
    pub a: f64,
    /// Steps spent accelerating (real) and the time to do so.
    x1: f64,
    t1: f64,
    /// Total duration.
    total: f64,
    /// Speed at the top of the profile.
    peak: f64,
}

impl Trapezoid {
    /// `v` and `a` must be positive and finite (a `HeadConfig`'s are).
    pub fn new(n: u32, v: f64, a: f64) -> Self {
        let nf = n as f64;
        let (x1, peak) = if v * v / a >= nf {
            // Triangular: half the way up, half down.
            (nf / 2.0, libm::sqrt(a * nf))
        } else {
            (v * v / (2.0 * a), v)
        };
        let t1 = peak / a;
        let total = if n == 0 { 0.0 } else { 2.0 * t1 + (nf - 2.0 * x1) / peak };
        Trapezoid {
            n,
            v,
            a,
            x1,
            t1,
            total,
            peak,
        }
    }

    /// Time (s) of step `k` (1 ≤ k ≤ n) from the start of the move.
    pub fn step_time(&self, k: u32) -> f64 {
        let (k, n) = (k as f64, self.n as f64);
        if k <= self.x1 {
            libm::sqrt(2.0 * k / self.a)
        } else if k <= n - self.x1 {
            self.t1 + (k - self.x1) / self.peak
        } else {
            self.total - libm::sqrt(2.0 * (n - k).max(0.0) / self.a)
        }
    }

    /// Last step of the acceleration and last step of the cruise, as
    /// [`Trapezoid::step_time`] tells the phases apart.
    pub fn phase_ends(&self) -> (u32, u32) {
        (self.x1 as u32, (self.n as f64 - self.x1) as u32)
    }

    pub fn duration(&self) -> f64 {
        self.total
    }
}
