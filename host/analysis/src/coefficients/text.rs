//! Coefficients as a table for a terminal, as `gonio coefficients` prints
//! them: each value rounded to its uncertainty, with what it rests on and,
//! where it is not measured, why and what scan would measure it.

use super::{Coefficient, Kind, Provenance};
use crate::instrument::Instrument;
use crate::rounding::{significant, with_uncertainty};
use std::fmt;

/// The values, at the instrument they rest on (`None`: a model's).
pub struct Table<'a> {
    pub values: &'a [Coefficient],
    pub instrument: Option<Instrument>,
}

impl fmt::Display for Table<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.instrument {
            Some(i) => writeln!(f, "at {}, not photometric; u: standard uncertainty (k = 1)", i.wavelength_text())?,
            None => writeln!(
                f,
                "a model's values: at no instrument's wavelength, not photometric; u: standard uncertainty (k = 1)"
            )?,
        }
        writeln!(
            f,
            "{:<4} {:>6} {:>7} {:>6} {:>8} {:>8} {:>8} {:>25}  {:<12} unit",
            "", "α°", "β°", "ε°", "θi°", "θo°", "Δφ°", "value ± u (k = 1)", "rests on"
        )?;
        for c in self.values {
            row(f, c)?;
        }
        Ok(())
    }
}

/// One coefficient's line, and the lines saying what it rests on.
fn row(f: &mut fmt::Formatter<'_>, c: &Coefficient) -> fmt::Result {
    let (g, e) = (&c.request.geometry, &c.estimate);
    let [ti, to, dp] = c.sample_angles_deg;
    let name = match c.request.kind {
        Kind::Ra => "R_A",
        Kind::Rl => "R_L",
    };
    let rests_on = match &e.basis {
        Some(b) if b.provenance == Provenance::Extrapolated => "EXTRAPOLATED",
        Some(b) if b.provenance == Provenance::NotMeasured => "NOT MEASURED",
        Some(b) => b.provenance.name(),
        None => "",
    };
    let value = match e.value.is_nan() {
        true => "—".to_string(),
        false => with_uncertainty(e.value, e.u),
    };
    writeln!(
        f,
        "{name:<4} {:>6.2} {:>7.2} {:>6.1} {ti:>8.3} {to:>8.3} {dp:>8.2} {value:>25}  {rests_on:<12} {}",
        g.alpha_deg,
        g.beta_deg(),
        g.epsilon_deg,
        c.request.kind.unit()
    )?;
    if let Some(b) = e.basis.as_ref().filter(|b| !b.provenance.on_data()) {
        match (e.model, e.u_model) {
            (Some(m), Some(um)) => writeln!(
                f,
                "       {}: carried by {m}; {} models carry it, their spread ±{}",
                b.why,
                e.models.len(),
                significant(um, 2)
            )?,
            _ => writeln!(f, "       {}", b.why)?,
        }
        if let Some(m) = b.measure.as_ref().filter(|_| e.value.is_nan()) {
            writeln!(f, "       measure it: {m}")?;
        }
    }
    if let Some(n) = e.nearest.first() {
        let names: Vec<String> = e
            .nearest
            .iter()
            .map(|n| format!("({:.2}°, {:.2}°, {:.1}°)", n.theta_i_deg, n.theta_o_deg, n.dphi_deg))
            .collect();
        writeln!(
            f,
            "       from the measured geometries {} (the nearest {:.3}° away)",
            names.join(", "),
            n.distance_deg
        )?;
    }
    Ok(())
}
