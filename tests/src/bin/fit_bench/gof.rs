//! The `gof` section: a right model fitted with right σ draws its reduced
//! χ² from the χ² distribution of N − k degrees of freedom, so it lies in
//! that distribution's 99 % interval in 99 % of trials (bar: ≥ 98 % of
//! 200). Every model, each trial its own noise draw of 500 samples at 2 %,
//! fitted from no start (the global search), as a user fits.

use gonio_analysis::fit::goodness::Goodness;
use gonio_analysis::fit::{self, FitSpec, Weighting};
use gonio_brdf::ModelId;
use gonio_tests::synthetic;
use serde_json::{json, Map, Value};

use crate::NOISE;

const TRIALS: u64 = 200;
const SAMPLES: usize = 500;

/// Per model the share of trials inside the interval; returns the table
/// and the smallest share.
pub fn gof() -> (Value, f64) {
    let mut table = Map::new();
    let mut worst = 1.0f64;
    for model in ModelId::ALL {
        let truth = synthetic::reference(model);
        let spec = FitSpec {
            weighting: Weighting::Sigma,
            ..FitSpec::new(model)
        };
        let (mut inside, mut p_low, mut seconds) = (0u64, 0u64, 0.0);
        let mut interval = (0.0, 0.0);
        for trial in 1..=TRIALS {
            let data = synthetic::samples(&truth, SAMPLES, NOISE, 5000 + trial);
            let f = fit::fit(&data, &spec).expect("σ-weighted fit");
            let g = f.goodness.expect("χ² of a σ-weighted fit");
            interval = Goodness::interval(g.dof, 0.99);
            inside += u64::from((interval.0..=interval.1).contains(&g.reduced_chi2));
            p_low += u64::from(g.p_value < 0.01);
            seconds += f.seconds;
        }
        let share = inside as f64 / TRIALS as f64;
        worst = worst.min(share);
        eprintln!(
            "gof    {:<16} inside {inside}/{TRIALS}  p<0.01 {p_low}  {seconds:.1} s",
            model.name()
        );
        table.insert(
            model.name().into(),
            json!({
                "inside": inside, "trials": TRIALS, "share_inside": share, "p_below_0_01": p_low,
                "interval_99": [interval.0, interval.1], "samples": SAMPLES, "seconds": seconds,
            }),
        );
    }
    (Value::Object(table), worst)
}
