//! `cargo run --release -p gonio-bench --bin lockin-bench`: figures of merit of the
//! head's synchronous detector, as one JSON object on stdout (a table on
//! stderr). Every figure is measured here, in this run:
//!
//! - `efficiency`: Cramér–Rao bound of the amplitude of the known waveform in
//!   white noise, `σ²/Σ(s−s̄)²`, over the measured variance, both relative to
//!   the squared mean amplitude (so a constant scale of the estimate, such as
//!   the boxcar-equivalent scale of the matched reference, cancels). σ² includes
//!   the 12-bit quantisation (1/12 code²). Also reported for the square and sine
//!   references.
//! - `mains50_error`, `mains60_error`: the amplitude error that 10·A of pickup
//!   adds, relative to A: each trial draws a pickup phase and one noise draw,
//!   used with and without the pickup; the paired differences are fitted with
//!   `c + α·cos φ + β·sin φ` (the response of any linear estimator to pickup of
//!   phase φ) and the figure is its worst case over φ, `|c| + √(α² + β²)`.
//!   The raw RMS of the paired differences is reported too
//!   (`mains50_paired_rms`): it is dominated by 12-bit quantisation, which
//!   rounds the two signals differently; `quantisation_floor` is the same RMS
//!   for a disturbance the estimator rejects exactly (a half-code offset step).
//!   A is the largest chop that leaves room for ±10·A of pickup in 12 bits.
//! - `drift_error`: RMS over trials of the amplitude change a linear offset
//!   drift of 10·A across the window causes (same noise draw), relative to A.
//! - `idsp_ratio`: RMS amplitude error of ours over that of idsp's `Lockin`
//!   on the same codes (white noise and 50 Hz pickup), 100 ms per point, both
//!   starting cold. Fairness: both get the identical samples; idsp gets them
//!   about mid-scale as a bipolar front end would; its LO is the chop
//!   fundamental; its second-order Butterworth lowpass corner is the best of a
//!   sweep; its output is projected on its own noise-free phase and both
//!   estimates are scaled by their noise-free response, so neither pays for a
//!   gain or phase convention.
//! - `throughput_msps`, `idsp_throughput_msps`: host samples per second.

use dsp_process::SplitProcess;
use gonio_bench::chop_signal::ChopSignal;
use gonio_firmware::demod::{Integrator, Learned, Learner, Reference};
use gonio_shared::Reference as Kind;
use idsp::{Lockin, Lowpass, LowpassState};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::hint::black_box;
use std::num::Wrapping;
use std::time::Instant;

const TRIALS: usize = 20_000;
const PAIRED_TRIALS: usize = 1_000;
const IDSP_TRIALS: usize = 2_000;

fn ours(r: &Reference, sig: &ChopSignal, codes: &[u16]) -> f64 {
    let mut it = Integrator::new(r, sig.periods as u32, sig.chop_hz);
    for p in codes.chunks(sig.samples_per_period) {
        it.push(p);
    }
    it.estimate().amplitude
}

/// Learning as the head does it: one second of a strong chop.
fn learn(sig: &ChopSignal, rng: &mut StdRng) -> Learned {
    let cal = ChopSignal {
        amplitude: 1500.0,
        offset: 1200.0,
        periods: 230,
        drift: 0.0,
        mains: None,
        ..sig.clone()
    };
    let codes = ChopSignal::quantise(&cal.analog(&cal.unit_response(), rng));
    let mut l = Learner::new(cal.samples_per_period, cal.periods as u32, cal.chop_hz);
    for p in codes.chunks(cal.samples_per_period) {
        l.push(p);
    }
    l.finish().expect("learning periods")
}

fn mean_var(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    (m, x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0))
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// CRB / measured relative variance for one reference; and the relative CRB.
fn efficiency(r: &Reference, sig: &ChopSignal, rng: &mut StdRng) -> (f64, f64) {
    let unit = sig.unit_response();
    let mean_s = unit.iter().sum::<f64>() / unit.len() as f64;
    let energy: f64 = unit.iter().map(|s| (s - mean_s).powi(2)).sum();
    let sigma2 = sig.noise * sig.noise + 1.0 / 12.0;
    let crb_rel = sigma2 / energy / (sig.amplitude * sig.amplitude);
    let est: Vec<f64> = (0..TRIALS)
        .map(|_| ours(r, sig, &ChopSignal::quantise(&sig.analog(&unit, rng))))
        .collect();
    let (m, v) = mean_var(&est);
    (crb_rel / (v / (m * m)), crb_rel)
}

/// Relative change of the estimate when `disturb` (at a random phase) is
/// applied, same noise draw: `(phase, change)` per trial.
fn paired(r: &Reference, base: &ChopSignal, disturb: impl Fn(&ChopSignal, f64) -> ChopSignal, seed: u64) -> Vec<(f64, f64)> {
    let unit = base.unit_response();
    let mut phases = StdRng::seed_from_u64(seed);
    (0..PAIRED_TRIALS)
        .map(|t| {
            let ph = phases.random_range(0.0..std::f64::consts::TAU);
            let noisy = |s: &ChopSignal| ChopSignal::quantise(&s.analog(&unit, &mut StdRng::seed_from_u64(seed ^ (t as u64) << 20)));
            (
                ph,
                (ours(r, base, &noisy(&disturb(base, ph))) - ours(r, base, &noisy(base))) / base.amplitude,
            )
        })
        .collect()
}

fn paired_rms(d: &[(f64, f64)]) -> f64 {
    rms(&d.iter().map(|x| x.1).collect::<Vec<_>>())
}

/// Worst case over the pickup phase of the fitted response `c + α cos φ + β sin φ`.
fn phase_locked(d: &[(f64, f64)]) -> f64 {
    // Normal equations of the three-term fit, solved by Cramer's rule.
    let g = |p: f64| [1.0, p.cos(), p.sin()];
    let mut a = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for &(p, y) in d {
        let v = g(p);
        for i in 0..3 {
            b[i] += v[i] * y;
            for j in 0..3 {
                a[i][j] += v[i] * v[j];
            }
        }
    }
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d0 = det(&a);
    let x: Vec<f64> = (0..3)
        .map(|c| {
            let mut m = a;
            for r in 0..3 {
                m[r][c] = b[r];
            }
            det(&m) / d0
        })
        .collect();
    x[0].abs() + x[1].hypot(x[2])
}

/// idsp's lock-in over one point's codes; returns its output phasor.
fn idsp_point(lp: &Lockin<Lowpass<2>>, sig: &ChopSignal, codes: &[u16]) -> (f64, f64) {
    let mut state: [LowpassState<2>; 2] = Default::default();
    let step = Wrapping((1u64 << 32).div_euclid(sig.samples_per_period as u64) as u32 as i32);
    let mut phase = Wrapping(0i32);
    let mut out = idsp::Complex::new(0i32, 0i32);
    for &c in codes {
        out = lp.process(&mut state, ((c as i32 - 2048) << 18, phase));
        phase += step;
    }
    (out.re() as f64, out.im() as f64)
}

fn idsp_lockin(sig: &ChopSignal, corner_hz: f64) -> Lockin<Lowpass<2>> {
    let fnyq = sig.sample_rate_hz() / 2.0;
    let k = std::f64::consts::PI * (1u64 << 31) as f64 * corner_hz / fnyq;
    let q = std::f64::consts::FRAC_1_SQRT_2;
    Lockin(Lowpass([(k * k / (1u64 << 32) as f64) as i32, (-k / q) as i32]))
}

/// RMS relative amplitude error of idsp at a corner, scaled by its noise-free response.
fn idsp_rms(sig: &ChopSignal, corner_hz: f64, trials: &[Vec<u16>], clean: &[u16]) -> f64 {
    let lp = idsp_lockin(sig, corner_hz);
    let (cr, ci) = idsp_point(&lp, sig, clean);
    let (mag, ph) = ((cr * cr + ci * ci).sqrt(), ci.atan2(cr));
    let errs: Vec<f64> = trials
        .iter()
        .map(|codes| {
            let (re, im) = idsp_point(&lp, sig, codes);
            (re * ph.cos() + im * ph.sin()) / mag - 1.0
        })
        .collect();
    rms(&errs)
}

fn throughput(mut f: impl FnMut() -> usize) -> f64 {
    let t = Instant::now();
    let mut n = 0;
    while t.elapsed().as_secs_f64() < 1.0 {
        n += f();
    }
    n as f64 / t.elapsed().as_secs_f64() / 1e6
}

fn main() {
    let mut rng = StdRng::seed_from_u64(20261123);
    let sig = ChopSignal::reference(100.0, 20.0);
    let learned = learn(&sig, &mut rng);
    let m = sig.samples_per_period;
    let matched = Reference::new(Kind::Matched, m, Some(&learned));
    assert!(matched.is_matched());
    let (eff, crb_rel) = efficiency(&matched, &sig, &mut rng);
    let (eff_square, _) = efficiency(&Reference::new(Kind::Square, m, Some(&learned)), &sig, &mut rng);
    let (eff_sine, _) = efficiency(&Reference::new(Kind::Sine, m, Some(&learned)), &sig, &mut rng);

    // Room in 12 bits for a chop A plus ±10·A of pickup or 10·A of drift.
    let a = 180.0;
    let base = ChopSignal {
        offset: 2048.0 - a / 2.0,
        ..ChopSignal::reference(a, 2.0)
    };
    let with_mains = |hz: f64| {
        move |s: &ChopSignal, ph: f64| ChopSignal {
            mains: Some((10.0 * a, hz, ph)),
            ..s.clone()
        }
    };
    let pairs50 = paired(&matched, &base, with_mains(50.0), 50);
    let pairs60 = paired(&matched, &base, with_mains(60.0), 60);
    let (mains50, mains60) = (phase_locked(&pairs50), phase_locked(&pairs60));
    let floor = paired_rms(&paired(
        &matched,
        &base,
        |s, _| ChopSignal {
            offset: s.offset + 0.5,
            ..s.clone()
        },
        5,
    ));
    let drift = paired_rms(&paired(
        &matched,
        &base,
        |s, _| ChopSignal {
            offset: s.offset - 5.0 * a,
            drift: 10.0 * a,
            ..s.clone()
        },
        7,
    ));

    // Ours against idsp: white noise and 50 Hz pickup, 100 ms per point.
    let cmp = ChopSignal {
        noise: 20.0,
        ..base.clone()
    };
    let unit = cmp.unit_response();
    let trials: Vec<Vec<u16>> = (0..IDSP_TRIALS)
        .map(|_| {
            let s = ChopSignal {
                mains: Some((10.0 * a, 50.0, rng.random_range(0.0..std::f64::consts::TAU))),
                ..cmp.clone()
            };
            ChopSignal::quantise(&s.analog(&unit, &mut rng))
        })
        .collect();
    let clean_sig = ChopSignal { noise: 0.0, ..cmp.clone() };
    let clean = ChopSignal::quantise(&clean_sig.analog(&unit, &mut rng));
    let our_scale = ours(&matched, &cmp, &clean) / a;
    let our_errs: Vec<f64> = trials.iter().map(|c| ours(&matched, &cmp, c) / our_scale / a - 1.0).collect();
    let our_rms = rms(&our_errs);
    let sweep = [2.0, 5.0, 10.0, 15.0, 20.0, 30.0, 40.0, 60.0, 80.0, 120.0, 160.0];
    let (best_corner, _) = sweep
        .iter()
        .map(|&f| (f, idsp_rms(&cmp, f, &trials[..300], &clean)))
        .min_by(|x, y| x.1.total_cmp(&y.1))
        .unwrap_or((20.0, f64::NAN));
    let idsp_err = idsp_rms(&cmp, best_corner, &trials, &clean);

    // Host throughput on the same buffers.
    let ours_msps = throughput(|| {
        for c in &trials[..200] {
            black_box(ours(&matched, &cmp, black_box(c)));
        }
        200 * cmp.len()
    });
    let lp = idsp_lockin(&cmp, best_corner);
    let idsp_msps = throughput(|| {
        for c in &trials[..200] {
            black_box(idsp_point(&lp, &cmp, black_box(c)));
        }
        200 * cmp.len()
    });

    let out = serde_json::json!({
        "efficiency": eff,
        "efficiency_square": eff_square,
        "efficiency_sine": eff_sine,
        "crb_relative_sd": crb_rel.sqrt(),
        "trials": TRIALS,
        "mains50_error": mains50,
        "mains60_error": mains60,
        "mains50_paired_rms": paired_rms(&pairs50),
        "mains60_paired_rms": paired_rms(&pairs60),
        "quantisation_floor": floor,
        "drift_error": drift,
        "paired_trials": PAIRED_TRIALS,
        "idsp_ratio": our_rms / idsp_err,
        "rms_error": our_rms,
        "idsp_rms_error": idsp_err,
        "idsp_corner_hz": best_corner,
        "idsp_version": "0.23.1",
        "throughput_msps": ours_msps,
        "idsp_throughput_msps": idsp_msps,
    });
    eprintln!("lock-in benchmark (64 samples/period, 23 periods at 230 Hz, τ = 5 % of the period)");
    eprintln!("  efficiency       matched {eff:.4}  square {eff_square:.4}  sine {eff_sine:.4}   (≥ 0.95)");
    eprintln!(
        "  mains 50/60 Hz   {mains50:.2e} / {mains60:.2e}   (≤ 1e-4); paired rms {:.2e} / {:.2e}, quantisation floor {floor:.2e}",
        paired_rms(&pairs50),
        paired_rms(&pairs60)
    );
    eprintln!("  drift            {drift:.2e}   (≤ 1e-3)");
    eprintln!(
        "  vs idsp          rms {our_rms:.4} vs {idsp_err:.4} (corner {best_corner} Hz), ratio {:.3} (≤ 1)",
        our_rms / idsp_err
    );
    eprintln!("  throughput       {ours_msps:.0} MS/s vs idsp {idsp_msps:.0} MS/s");
    println!("{out}");
}
