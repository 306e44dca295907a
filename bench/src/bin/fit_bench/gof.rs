//! The `gof` section: a right model fitted with right σ draws its reduced
//! χ² from the χ² distribution of N − k degrees of freedom, so it lies in
//! that distribution's 99 % interval in 99 % of trials. Every model, 200
//! trials each, each trial its own noise draw of 500 samples at 2 %, fitted
//! from no start (the global search), as a user fits. Bar: ≥ 98 % of all
//! the trials, pooled. Per model it would fail a right engine too often:
//! 196 of 200 at p = 0.99 is reached with probability 0.948, all nine
//! models together 0.62; pooled (1 800 trials, σ 0.23 %) 98 % is 4.3 σ
//! below the expected 99 %. Each model must also reach 95 % (190 of 200,
//! which a right engine misses with probability below 1e-5): a model far
//! off is not hidden by the pool.

use gonio_analysis::fit::goodness::Goodness;
use gonio_analysis::fit::{self, FitSpec, Weighting};
use gonio_brdf::ModelId;
use gonio_tests::synthetic;
use serde_json::{json, Map, Value};

use crate::NOISE;

const TRIALS: u64 = 200;
const SAMPLES: usize = 500;

/// Per model the share of trials inside the interval; returns the table,
/// the share of all the trials and the smallest model's.
pub fn gof() -> (Value, f64, f64) {
    let mut table = Map::new();
    let mut pooled = 0u64;
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
        pooled += inside;
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
    (
        Value::Object(table),
        pooled as f64 / (TRIALS as usize * ModelId::ALL.len()) as f64,
        worst,
    )
}
