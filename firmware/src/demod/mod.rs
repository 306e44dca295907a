//! Synchronous detection in integers, one chop period at a time.
//!
//! Each period of M codes is correlated with reference waveforms
//! ([`reference`]): an in-phase and a quadrature square or sine, and — once
//! [`learn`] has learned it on a strong signal — the signal's own waveform
//! (the matched reference: the least-squares amplitude of a known waveform in
//! white noise, which reaches the Cramér–Rao bound). Every reference sums to
//! zero over a period, so constant offsets (ambient light, amplifier offset)
//! cancel exactly.
//!
//! What a periodic reference cannot cancel is handled per period by
//! [`nuisance`]: a linear drift of the offset adds the same bias to every
//! period, `slope · Σ k·r_k`; the drift slope is estimated from the per-period
//! sums of codes, with mains pickup (50/60 Hz and harmonics, aliased by the
//! chop rate) fitted alongside so it cannot leak into the slope, and the bias
//! is removed. Mains pickup itself cancels in the correlation sums over a
//! window of whole mains periods (23 periods at 230 Hz = 100 ms = 5 × 50 Hz =
//! 6 × 60 Hz) and is fitted out of the per-period spread that gives the
//! standard error.
//!
//! Ranges: a code is < 2^12, a reference value ≤ 2^14, M ≤ 512, so one
//! period's correlation sum is < 2^35 (i64) and a 10 s integration at 5 kHz
//! chop (50 000 periods) stays below 2^51. Per-period statistics are f64.

mod integrator;
mod learn;
mod learned;
mod nuisance;
mod reference;

pub use integrator::{Estimate, Integrator};
pub use learn::Learner;
pub use learned::{Learned, MAX_M};
pub use nuisance::Design;
pub use reference::{Period, Reference};
