//! The samples a fit sees and those it is judged on: a data set restricted
//! to some incidences or to the retro half-space, with incidences held out
//! to test how well a fit predicts what it did not see (cross-validation,
//! as Zhang et al.).

use super::data::theta_in;
use super::Dataset;
use anyhow::{bail, Result};

/// Which samples to keep, and which incidences to hold out (degrees).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Restriction {
    /// The retro half-space only (|Δφ| ≤ 90°).
    pub retro_only: bool,
    /// Only these incidences (none: every one).
    pub theta_i_deg: Vec<f64>,
    pub holdout_theta_i_deg: Vec<f64>,
}

/// The samples fitted, and those held out.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    pub train: Dataset,
    pub holdout: Option<Dataset>,
}

/// `15°, 30°, 60°`.
fn degrees(angles: &[f64]) -> String {
    angles.iter().map(|a| format!("{a}°")).collect::<Vec<_>>().join(", ")
}

/// `data` (read from `source`, named in messages) restricted by `r`; a
/// restriction that leaves nothing to fit or to hold out is refused with
/// the incidences the data hold.
pub fn select(data: Dataset, r: &Restriction, source: &str) -> Result<Selection> {
    let held = degrees(&data.incidence_angles_deg());
    let data = data.filter(|s| (!r.retro_only || s.on_retro_side()) && (r.theta_i_deg.is_empty() || theta_in(s.theta_i, &r.theta_i_deg)));
    let (train, holdout) = if r.holdout_theta_i_deg.is_empty() {
        (data, None)
    } else {
        let h = data.filter(|s| theta_in(s.theta_i, &r.holdout_theta_i_deg));
        if h.observations.is_empty() {
            bail!(
                "no samples to hold out at θi = {}: {source} holds θi = {held}",
                degrees(&r.holdout_theta_i_deg)
            );
        }
        (data.filter(|s| !theta_in(s.theta_i, &r.holdout_theta_i_deg)), Some(h))
    };
    if train.observations.is_empty() {
        bail!("no samples left to fit after the restrictions (--theta-i, --retro-only, --holdout-theta-i): {source} holds θi = {held}");
    }
    Ok(Selection { train, holdout })
}
