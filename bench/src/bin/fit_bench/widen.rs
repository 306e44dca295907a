//! The `widen` section: every misfit case fitted again with each default
//! box cut at its open edges to what one widening (`Bound::widened`) grows
//! back to the full box, about a tenth. A fit whose boxes, cut and then
//! widened, hold the full-box fit's optimum (`holds_full_optimum`) must end
//! at least as low as the full-box fit: RMSE ratio ≤ 1 + 1e-9. Where the
//! optimum of a cut box never touched one of its cut open edges (it lies
//! inside, or on a physical limit) nothing tells the fit that box is too
//! small: the case is listed with the parameters whose full-box optimum is
//! beyond (`full_optimum_outside`) and its ratio, outside the bar; what
//! guards those is the default box's size.

use gonio_analysis::fit::{self, FitSpec};
use gonio_brdf::{Bound, Spread};
use serde_json::{json, Value};

use crate::cases::cases;

/// The box `b` cut at its open edges so that one widening restores it
/// (empty or inverted where a log box spans no more than the growth: the
/// caller keeps those whole).
fn cut(b: &Bound) -> Bound {
    let g = Bound::GROWTH;
    let (mut lo, mut hi) = (b.lo, b.hi);
    match (b.spread, b.open) {
        (_, (false, false)) => {}
        (Spread::Log, (low, high)) if lo > 0.0 => {
            if low {
                lo *= g;
            }
            if high {
                hi /= g;
            }
        }
        (_, (low, high)) => {
            // A width w widened at k open edges becomes w·(1 + k·(g − 1)).
            let w = (hi - lo) / (1.0 + (g - 1.0) * f64::from(u8::from(low) + u8::from(high)));
            if low {
                lo = hi - w;
                if high {
                    lo -= (g - 1.0) * w;
                }
            }
            if high {
                hi = lo + w;
            }
        }
    }
    Bound { lo, hi, ..*b }
}

/// The first `limit` cases whose label holds `filter`; returns the table,
/// the largest RMSE ratio − 1 of the cases whose boxes hold the full-box
/// optimum, and how many did.
pub fn widen(limit: usize, filter: &str) -> (Value, f64, usize) {
    let mut rows = Vec::new();
    let mut worst = 0.0f64;
    let mut holding = 0;
    for case in cases().into_iter().filter(|c| c.label().contains(filter)).take(limit) {
        let data = &*case.data;
        let spec = FitSpec::new(case.model);
        let full = fit::fit(data, &spec).expect("full-box fit");
        let defaults = fit::problem(data, &spec).expect("problem").bounds_all;
        let boxes: Vec<(usize, f64, f64)> = defaults
            .iter()
            .enumerate()
            .filter(|(_, b)| b.open != (false, false) && cut(b).lo < cut(b).hi)
            .map(|(i, b)| {
                let c = cut(b);
                let back = c.widened(c.open).expect("an open box widens");
                assert!(
                    (back.lo - b.lo).abs() <= 1e-12 * (b.hi - b.lo) && (back.hi - b.hi).abs() <= 1e-12 * (b.hi - b.lo),
                    "cut {c:?} does not widen back to {b:?}"
                );
                (i, c.lo, c.hi)
            })
            .collect();
        let cut_fit = fit::fit(
            data,
            &FitSpec {
                default_boxes: boxes.clone(),
                ..spec
            },
        )
        .expect("cut-box fit");
        let ratio = cut_fit.metrics.rmse / full.metrics.rmse;
        let names = case.model.param_names();
        // The box each cut parameter ended in, and those that do not hold
        // the full-box optimum.
        let outside: Vec<&str> = boxes
            .iter()
            .filter(|&&(i, lo, hi)| {
                let (lo, hi) = cut_fit
                    .widened
                    .iter()
                    .find(|(n, _)| *n == names[i])
                    .map_or((lo, hi), |(_, w)| (w.lo, w.hi));
                let (v, tol) = (full.material.params[i], 1e-9 * (hi - lo));
                v < lo - tol || v > hi + tol
            })
            .map(|b| names[b.0])
            .collect();
        if outside.is_empty() {
            worst = worst.max(ratio - 1.0);
            holding += 1;
        }
        eprintln!(
            "widen  {:<40} rmse ratio {ratio:.12}  widened {:?}  full optimum outside {outside:?}  ({:.2} s vs {:.2} s)",
            case.label(),
            cut_fit.widened.iter().map(|w| w.0).collect::<Vec<_>>(),
            cut_fit.seconds,
            full.seconds
        );
        rows.push(json!({
            "samples": case.samples, "material": case.material, "model": case.model.name(),
            "rmse": cut_fit.metrics.rmse, "full_box_rmse": full.metrics.rmse, "rmse_ratio": ratio,
            "cut": boxes.iter().map(|&(i, lo, hi)| (names[i].to_string(), json!([lo, hi]))).collect::<serde_json::Map<_, _>>(),
            "widened": cut_fit.widened.iter().map(|w| w.0).collect::<Vec<_>>(),
            "holds_full_optimum": outside.is_empty(), "full_optimum_outside": outside,
            "at_bound": cut_fit.at_bound, "full_box_at_bound": full.at_bound,
            "seconds": cut_fit.seconds, "full_box_seconds": full.seconds,
        }));
    }
    (Value::Array(rows), worst, holding)
}
