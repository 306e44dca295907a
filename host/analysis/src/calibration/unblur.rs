//! Swept samples' blur taken out of their calibrated values, along their
//! rows (a swept sample averages the BRDF over its path).

use super::CalibratedRow;

/// Neighbours a side a sample's correction takes along its row.
const REACH: usize = 2;
/// Neighbours' extents within this ratio of the sample's: beyond it the
/// polynomial through them no longer describes the sample's own path.
const EVEN: f32 = 3.0;

/// Takes out what their extent adds to swept samples' calibrated values. A
/// swept sample averages `f` over its path (the demodulation weighs its
/// periods alike): on the flank of a narrow lobe that average lies well
/// above the value at its middle (`h²·f''/24` for an extent `h`: 2 % for the
/// tape's lobe, n = 500, at ψ = 5.5° and `h` = 1°, 7 % at 9°). The samples of
/// a row abut (each begins where the previous ended), so the polynomial
/// whose averages over a sample and its neighbours (two a side, a quartic;
/// one, a quadratic, next to a row's ends) are the measured ones gives `f`
/// at the sample's middle, whatever the extents: in the ramps at a row's
/// ends, where the arm speeds up over its first 7.5° and slows over its
/// last, neighbours differ in length (a correction that assumes them equal,
/// `B − Δ²B/24 + 3·Δ⁴B/640`, leaves a fifth of the blur there, where the
/// tape's lobe is; `scan-bench`'s `fit_agreement` compares the fits). The
/// noise grows by about a tenth; the uncertainty budget is not widened for
/// it. Samples at
/// rest, at a row's ends, or beside an unusable one are left as they are.
pub fn unblur(rows: &mut [CalibratedRow]) {
    // Samples k and k + 1 abut along one row.
    let abut = |k: usize| {
        let (a, b) = (&rows[k], &rows[k + 1]);
        a.raw.order.is_some() && a.raw.order == b.raw.order && a.raw.seq.wrapping_add(1) == b.raw.seq && a.usable && b.usable
    };
    let extent = |k: usize| rows[k].raw.extent_deg.filter(|h| *h > 0.0);
    // The neighbours within `reach` of k abut it and are not much longer
    // or shorter.
    let reaches = |k: usize, reach: usize| {
        k >= reach
            && k + reach < rows.len()
            && (k - reach..k + reach).all(abut)
            && extent(k).is_some_and(|h| (k - reach..=k + reach).all(|j| extent(j).is_some_and(|e| e <= EVEN * h && h <= EVEN * e)))
    };
    let corrected: Vec<Option<f64>> = (0..rows.len())
        .map(|k| {
            let reach = (1..=REACH).rev().find(|&r| reaches(k, r))?;
            let window: Vec<(f64, f64)> = (k - reach..=k + reach)
                .map(|j| (extent(j).unwrap_or(0.0) as f64, rows[j].brdf_sr))
                .collect();
            at_middle(&window, reach)
        })
        .collect();
    for (r, c) in rows.iter_mut().zip(corrected) {
        let Some(c) = c else { continue };
        if r.brdf_sr != 0.0 {
            let ratio = c / r.brdf_sr;
            r.brdf_cos_sr *= ratio;
            r.shifts = r.shifts.map(|s| s * ratio);
        }
        r.brdf_sr = c;
    }
}

/// `f` at the middle of sample `mid` of abutting samples `(extent, average)`:
/// the polynomial of degree `len − 1` whose averages over the samples are
/// theirs, evaluated there.
fn at_middle(window: &[(f64, f64)], mid: usize) -> Option<f64> {
    let n = window.len();
    // Edges along the row, from the middle sample's centre.
    let mut edges = vec![0.0; n + 1];
    for (j, (h, _)) in window.iter().enumerate() {
        edges[j + 1] = edges[j] + h;
    }
    let centre = edges[mid] + 0.5 * window[mid].0;
    // The average of (x − centre)^p over sample j.
    let average = |j: usize, p: i32| {
        let (u, w) = (edges[j] - centre, edges[j + 1] - centre);
        (w.powi(p + 1) - u.powi(p + 1)) / ((p + 1) as f64 * (w - u))
    };
    let m = nalgebra::DMatrix::from_fn(n, n, |j, p| average(j, p as i32));
    let b = nalgebra::DVector::from_iterator(n, window.iter().map(|w| w.1));
    m.lu().solve(&b).map(|c| c[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::uncertainty::Components;
    use gonio_scan_dir::samples::Row;
    use gonio_shared::sample::ScanPosition;
    use gonio_shared::{AxisAngles, SweptSample};
    use gonio_shared::{SampleFlags, Signal};

    /// A narrow lobe along the arm's angle (degrees), `n = 500` as the
    /// tape's, over a diffuse floor.
    fn lobe(psi_deg: f64) -> f64 {
        0.02 + (psi_deg.to_radians().cos()).powi(500)
    }

    /// Samples of `h` degrees abutting from ψ = 6°, each the average of the
    /// lobe over its path, as a swept sample measures it.
    fn swept_row(h: f64, order: u32) -> Vec<CalibratedRow> {
        swept_spans(&[h; 12], order)
    }

    /// Samples of the given extents abutting from ψ = 6°.
    fn swept_spans(extents: &[f64], order: u32) -> Vec<CalibratedRow> {
        let edges: Vec<f64> = std::iter::once(6.0)
            .chain(extents.iter().scan(6.0, |x, h| {
                *x += h;
                Some(*x)
            }))
            .collect();
        (0..extents.len() as u32)
            .map(|k| {
                let (a, b) = (edges[k as usize], edges[k as usize + 1]);
                let average = (0..1000).map(|j| lobe(a + (b - a) * (j as f64 + 0.5) / 1000.0)).sum::<f64>() / 1000.0;
                let at = |psi: f64| AxisAngles {
                    omega_deg: 30.0,
                    tau_deg: 0.0,
                    psi_deg: psi as f32,
                };
                let s = SweptSample {
                    seq: 100 * order + k,
                    scan: Some(ScanPosition { index: order, order }),
                    start_us: 0,
                    duration_s: 0.035,
                    axes_from: at(a),
                    axes_to: at(b),
                    signal: Signal {
                        in_phase_v: 0.0,
                        quadrature_v: 0.0,
                        amplitude_v: 0.0,
                        magnitude_v: 0.0,
                        phase_deg: 0.0,
                        noise_v: 0.0,
                        gain_v_per_a: 1.0,
                        gain_index: 0,
                        periods: 8,
                        flags: SampleFlags::empty(),
                    },
                };
                CalibratedRow {
                    raw: Row::from(&s),
                    laser_power: 1.0,
                    usable: true,
                    brdf_sr: average,
                    brdf_sigma_sr: 0.0,
                    brdf_cos_sr: average,
                    budget: Components::default(),
                    shifts: [0.0; crate::uncertainty::SHARED.len()],
                }
            })
            .collect()
    }

    /// Largest error against the lobe at each sample's middle, relative to it,
    /// over samples `ks` of a row.
    fn worst(rows: &[CalibratedRow], h: f64, ks: std::ops::Range<usize>) -> f64 {
        ks.map(|k| {
            let mid = lobe(6.0 + (k as f64 + 0.5) * h);
            (rows[k].brdf_sr / mid - 1.0).abs()
        })
        .fold(0.0, f64::max)
    }

    #[test]
    fn a_swept_samples_extent_is_taken_out_of_its_value_along_its_row() {
        let h = 1.0;
        let blurred = swept_row(h, 3);
        let mut rows = blurred.clone();
        unblur(&mut rows);
        // Two neighbours a side: the error left is of order h⁶.
        let (before, after) = (worst(&blurred, h, 2..10), worst(&rows, h, 2..10));
        assert!(before > 0.01, "the lobe's curvature shows in 1° samples: {before}");
        assert!(after < before / 100.0, "corrected {after}, was {before}");
        // One a side (next to a row's ends): of order h⁴.
        let (before, after) = (worst(&blurred, h, 1..2), worst(&rows, h, 1..2));
        assert!(after < before / 10.0, "corrected {after}, was {before}");
        // A row's ends have a neighbour on one side only: left alone.
        assert_eq!(rows[0].brdf_sr, blurred[0].brdf_sr);
        assert_eq!(rows[11].brdf_sr, blurred[11].brdf_sr);
    }

    /// In a ramp (the arm speeding up from a row's start) the samples grow
    /// longer one after the other: corrected all the same.
    #[test]
    fn samples_of_unequal_extent_are_corrected_too() {
        let extents: Vec<f64> = (0..12).map(|k| 0.4 + 0.1 * k as f64).collect();
        let mut rows = swept_spans(&extents, 3);
        let blurred = rows.clone();
        unblur(&mut rows);
        let mut x = 6.0;
        let mut worst_before = 0.0f64;
        for (k, h) in extents.iter().enumerate() {
            let mid = lobe(x + 0.5 * h);
            x += h;
            if (2..10).contains(&k) {
                let (before, after) = (blurred[k].brdf_sr / mid - 1.0, rows[k].brdf_sr / mid - 1.0);
                worst_before = worst_before.max(before.abs());
                assert!(after.abs() < 2e-4, "sample {k}: {after} left of {before}");
            }
        }
        assert!(worst_before > 0.005, "the blur to take out: {worst_before}");
    }

    #[test]
    fn samples_of_other_rows_at_rest_or_unusable_are_not_neighbours() {
        let h = 1.0;
        // Two rows back to back: the samples at their seam keep their values.
        let mut rows = swept_row(h, 3);
        rows.extend(swept_row(h, 4));
        let before = rows.clone();
        rows[5].usable = false;
        unblur(&mut rows);
        for k in [4, 5, 6, 11, 12] {
            assert_eq!(rows[k].brdf_sr, before[k].brdf_sr, "sample {k}");
        }
        assert_ne!(rows[8].brdf_sr, before[8].brdf_sr);
        // At rest (no extent): untouched.
        let mut rest = swept_row(h, 5);
        for r in &mut rest {
            r.raw.extent_deg = None;
        }
        let kept = rest.clone();
        unblur(&mut rest);
        assert_eq!(rest, kept);
    }
}
