//! The retro lobe's moments as a table for a terminal, as `gonio moments`
//! prints them: angles to 0.01°, r to 0.001, and why an incidence has none.

use super::{Entry, Threshold};
use crate::rounding::{figure, significant};

/// The table of moments; `this_head`: the data are this head's, whose
/// blind zone explains a gap about the retro lobe (another instrument's
/// gaps are its own).
pub fn table(entries: &[Entry], threshold: Threshold, this_head: bool) -> String {
    let kept = match threshold {
        Threshold::Relative(q) => format!("f_r at or above {} % of its retro value", significant(100.0 * q, 3)),
        Threshold::Absolute(v) => format!("f_r at or above {} sr⁻¹", significant(v, 3)),
    };
    let mut out = format!(
        "retro lobe moments (Belcour et al. 2014 §3.D): {kept}, about the retro direction; angles in degrees\n\
         r = (σ²max − σ²min)/σ²min, 0 when isotropic; kurtosis 3 for a normal lobe\n\
         {:>6}  {:<10}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>8}  {:>7}  {:>7}  {:>7}\n",
        "θi", "plane", "samples", "gap/σ", "μx", "μy", "σx", "σy", "r", "ρxy", "kurt x", "kurt y"
    );
    for e in entries {
        let head = format!("{:>5}°  {:<10}", e.theta_i_deg, e.parametrization.name());
        match (&e.moments, &e.missing) {
            (Some(m), _) => {
                // Angles to 0.01°, finer than any head's stage; r to 0.001,
                // fine enough for the 0.05 that tells isotropy.
                out += &format!(
                    "{head}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>7}  {:>8}  {:>7}  {:>7}  {:>7}{}{}\n",
                    m.samples,
                    figure(m.gap_sigma, 2),
                    figure(m.mean_deg[0], 2),
                    figure(m.mean_deg[1], 2),
                    figure(m.sigma_deg[0], 2),
                    figure(m.sigma_deg[1], 2),
                    figure(m.r, 3),
                    figure(m.correlation, 2),
                    figure(m.kurtosis[0], 2),
                    figure(m.kurtosis[1], 2),
                    if m.under_sampled { "  *" } else { "" },
                    if m.truncated {
                        "  (truncated: the lobe reaches the edge of the data)"
                    } else {
                        ""
                    }
                );
            }
            (None, why) => out += &format!("{head}  none: {}\n", why.as_deref().unwrap_or_default()),
        }
    }
    if entries.iter().filter_map(|e| e.moments.as_ref()).any(|m| m.under_sampled) {
        out += "* samples more than a lobe width apart (gap/σ > 1): the lobe's outline and r follow the sampling";
        out += if this_head {
            " (the head's blind zone lies 5°–11.5° from the laser); a higher --threshold keeps the lobe within the retro rings\n"
        } else {
            "; a higher --threshold keeps the lobe where the samples are dense\n"
        };
    }
    if entries.iter().any(|e| e.mirrored) {
        out += "Δφ < 0 completed from Δφ > 0 by the isotropic BRDF's symmetry\n";
    }
    out
}
