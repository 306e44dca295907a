//! A rational fit as text for a terminal, as `gonio fit --model rational`
//! prints it: the function's plane, size and precision, the counts of
//! coefficients tried, and, for a densified fit, how much of the measured
//! data it still holds. What the user should weigh comes apart as notes.

use super::fit::RationalFit;
use super::qp::SINGLE_MARGIN;
use crate::fit::Metrics;
use crate::rounding::significant;
use std::fmt;

/// The fit, and how it predicts the incidences held out (`theta_i`, degrees).
pub struct RationalText<'a> {
    pub fit: &'a RationalFit,
    pub holdout: Option<(&'a [f64], &'a Metrics)>,
}

impl fmt::Display for RationalText<'_> {
    fn fmt(&self, out: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (f, r) = (self.fit, &self.fit.function);
        writeln!(
            out,
            "rational in the {} plane{} ({} samples, {:.2} s)",
            r.coordinates.name(),
            if r.cosine { ", times cosθi·cosθo" } else { "" },
            f.samples,
            f.seconds
        )?;
        writeln!(
            out,
            "  {} coefficients, degree {} ({} over {}); every segment held, segments {} of {}",
            r.coefficients(),
            r.degree,
            r.numerator.len(),
            r.denominator.len(),
            f.segments_text(),
            r.quantity.label()
        )?;
        let tried: Vec<String> = f
            .attempts
            .iter()
            .map(|t| {
                let held = if t.feasible { "held" } else { "not held" };
                let precision = if t.single_precision { "" } else { " in double" };
                format!("{} ({held}{precision})", t.coefficients)
            })
            .collect();
        writeln!(out, "  coefficients tried: {}", tried.join(", "))?;
        if let Some(d) = &f.densified {
            let m = &d.measured;
            let poles = match m.undefined {
                0 => String::new(),
                n => format!(", and has a pole (Q ≤ 0) at {n} of the samples"),
            };
            writeln!(
                out,
                "  fitted to {} points of a {}° grid between the samples; it holds {} of the {} measured segments (worst miss {} of a segment's width){poles}",
                d.points,
                d.step_deg,
                m.held,
                m.of,
                significant(m.worst, 2),
            )?;
        }
        writeln!(out, "  {}  L∞ {}", f.metrics.summary(), significant(f.linf, 4))?;
        if let Some((theta_i, h)) = self.holdout {
            writeln!(out, "  held out θi {theta_i:?}°: {}", h.summary())?;
        }
        Ok(())
    }
}

/// What the user should weigh: the densified grid's warnings, clamped
/// negative values, a capped search, and a function held in double
/// precision only.
pub fn notes(f: &RationalFit) -> Vec<String> {
    let mut notes: Vec<String> = f
        .densified
        .iter()
        .flat_map(|d| d.warnings.iter().map(|w| format!("warning: {w}")))
        .collect();
    if f.shifted > 0 {
        notes.push(format!(
            "note: {} value(s) were negative; their segments were clamped to [0, at least the half-width]: a BRDF is not negative",
            f.shifted
        ));
    }
    if let Some(c) = &f.capped {
        notes.push(format!("note: {c}"));
    }
    if !f.single_precision {
        notes.push(format!(
            "note: no function of up to {} coefficients holds every segment by the margin single precision needs ({SINGLE_MARGIN:e}): this one holds them in double precision only, and a shader or renderer evaluating it in single precision may leave some",
            f.attempts.iter().map(|t| t.coefficients).max().unwrap_or(0),
        ));
    }
    notes
}
