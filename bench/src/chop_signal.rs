//! A chopped photodiode signal for the lock-in benchmark and tests: an on/off
//! chop of amplitude A through a first-order amplifier (in steady state),
//! on an offset that may drift linearly, plus mains pickup and white Gaussian
//! noise, sampled M times per chop period and quantised to 12-bit codes.

use rand::Rng;
use rand_distr::StandardNormal;

#[derive(Debug, Clone, PartialEq)]
pub struct ChopSignal {
    pub samples_per_period: usize,
    pub periods: usize,
    pub chop_hz: f64,
    /// Amplifier time constant as a fraction of the chop period.
    pub tau_periods: f64,
    /// Chop amplitude and offset (codes).
    pub amplitude: f64,
    pub offset: f64,
    /// Offset change across the window (codes), linear.
    pub drift: f64,
    /// Mains pickup: amplitude (codes), frequency (Hz), phase (rad).
    pub mains: Option<(f64, f64, f64)>,
    /// White noise (codes rms).
    pub noise: f64,
}

impl ChopSignal {
    /// The benchmark's waveform: 64 samples per period, 23 periods at 230 Hz,
    /// time constant 5 % of the period.
    pub fn reference(amplitude: f64, noise: f64) -> Self {
        ChopSignal {
            samples_per_period: 64,
            periods: 23,
            chop_hz: 230.0,
            tau_periods: 0.05,
            amplitude,
            offset: 2048.0 - amplitude / 2.0,
            drift: 0.0,
            mains: None,
            noise,
        }
    }

    pub fn len(&self) -> usize {
        self.samples_per_period * self.periods
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn sample_rate_hz(&self) -> f64 {
        self.chop_hz * self.samples_per_period as f64
    }

    /// Noise-free steady-state response to a unit chop over the window.
    pub fn unit_response(&self) -> Vec<f64> {
        let m = self.samples_per_period;
        let a = (-1.0 / (m as f64 * self.tau_periods)).exp();
        let mut y = 0.0;
        // Twenty periods of history: the amplifier has long settled.
        let mut out = Vec::with_capacity(self.len());
        for k in 0..(20 * m + self.len()) {
            let x = if k % m < m / 2 { 1.0 } else { 0.0 };
            y = a * y + (1.0 - a) * x;
            if k >= 20 * m {
                out.push(y);
            }
        }
        out
    }

    /// The signal before quantisation, with noise drawn from `rng`.
    pub fn analog(&self, unit: &[f64], rng: &mut impl Rng) -> Vec<f64> {
        let n = self.len() as f64;
        let fs = self.sample_rate_hz();
        unit.iter()
            .enumerate()
            .map(|(k, s)| {
                let t = k as f64 / fs;
                let mains = self
                    .mains
                    .map_or(0.0, |(a, f, ph)| a * (2.0 * std::f64::consts::PI * f * t + ph).sin());
                let noise: f64 = rng.sample(StandardNormal);
                self.offset + self.drift * k as f64 / n + self.amplitude * s + mains + self.noise * noise
            })
            .collect()
    }

    /// 12-bit ADC codes of an analog signal.
    pub fn quantise(analog: &[f64]) -> Vec<u16> {
        analog.iter().map(|v| v.round().clamp(0.0, 4095.0) as u16).collect()
    }
}
