//! What a data set from a file needs before anything uses it: rows whose
//! stored quantity cannot give `f_r` dropped, and a geometry measured more
//! than once made one sample. Each is said in a warning, with how many
//! rows and why.

use super::data::{Dataset, Observation, GRAZING_DEG};
use std::collections::HashMap;

/// Angles closer than this (radians) are one geometry.
const SAME_RAD: f64 = 1e-6;

impl Dataset {
    /// Drops the rows too grazing for their units ([`GRAZING_DEG`]) and
    /// merges repeated geometries ([`Dataset::merge_repeats`]).
    pub fn settle(&mut self) {
        let n = self.observations.len();
        let units = self.units;
        self.observations.retain(|o| !o.too_grazing_for(units));
        let dropped = n - self.observations.len();
        if dropped > 0 {
            self.warnings.push(format!(
                "{dropped} of {n} rows dropped: their θo is beyond {GRAZING_DEG}°, where the file's f_r·cosθo cannot give f_r (cosθo < {:.4} would multiply the value and its noise by more than {:.0})",
                GRAZING_DEG.to_radians().cos(),
                1.0 / GRAZING_DEG.to_radians().cos()
            ));
        }
        if let Some(w) = self.merge_repeats() {
            self.warnings.push(w);
        }
    }

    /// Makes each geometry that appears more than once one sample: the
    /// mean of its values, with an uncertainty that adds their spread to
    /// what the rows state (`σ² = Σσᵢ²/n² + s²/n`, s the sample standard
    /// deviation). Returns what it did, for a warning; `None` when every
    /// geometry is there once.
    pub fn merge_repeats(&mut self) -> Option<String> {
        let mut groups: HashMap<[i64; 3], usize> = HashMap::new();
        let mut members: Vec<Vec<Observation>> = Vec::new();
        for o in &self.observations {
            let g = *groups.entry(geometry_key(o)).or_insert_with(|| {
                members.push(Vec::new());
                members.len() - 1
            });
            members[g].push(*o);
        }
        if members.len() == self.observations.len() {
            return None;
        }
        let n_rows = self.observations.len();
        let repeated: Vec<&Vec<Observation>> = members.iter().filter(|m| m.len() > 1).collect();
        let n_geometries = repeated.len();
        let n_repeated_rows: usize = repeated.iter().map(|m| m.len()).sum();
        // The widest relative spread, and where it is.
        let widest = repeated
            .iter()
            .map(|m| {
                let (lo, hi) = m
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), o| (l.min(o.value), h.max(o.value)));
                (if lo > 0.0 { hi / lo } else { f64::INFINITY }, m[0])
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        let any_sigma = repeated.iter().any(|m| m.iter().any(|o| o.sigma.is_some()));
        self.observations = members.into_iter().map(|m| merged(&m)).collect();
        let mut w = format!(
            "{n_geometries} {} more than once ({n_repeated_rows} of {n_rows} rows): each is merged to the mean of its values",
            if n_geometries == 1 {
                "geometry appears"
            } else {
                "geometries appear"
            }
        );
        w += if any_sigma {
            ", with their spread added to its uncertainty"
        } else {
            " (the file gives no uncertainty to add their spread to)"
        };
        if let Some((ratio, o)) = widest {
            let at = format!(
                "θi {:.2}°, θo {:.2}°, Δφ {:.2}°",
                o.theta_i.to_degrees(),
                o.theta_o.to_degrees(),
                o.dphi.to_degrees()
            );
            if ratio.is_finite() {
                w += &format!("; the widest spread, at {at}, is a factor {ratio:.3} between its values");
            } else {
                w += &format!("; at {at} the values do not share a sign");
            }
        }
        Some(w)
    }
}

/// The geometry of a row, to within [`SAME_RAD`]: Δφ taken in [0, 2π) and
/// meaningless (0) where either direction is the normal.
fn geometry_key(o: &Observation) -> [i64; 3] {
    let q = |x: f64| (x / SAME_RAD).round() as i64;
    let normal = o.theta_i < SAME_RAD || o.theta_o < SAME_RAD;
    let dphi = if normal { 0.0 } else { o.dphi.rem_euclid(std::f64::consts::TAU) };
    let dphi = if (std::f64::consts::TAU - dphi) < SAME_RAD { 0.0 } else { dphi };
    [q(o.theta_i), q(o.theta_o), q(dphi)]
}

/// One sample of the rows of one geometry.
fn merged(rows: &[Observation]) -> Observation {
    let n = rows.len() as f64;
    if rows.len() == 1 {
        return rows[0];
    }
    let mean = rows.iter().map(|o| o.value).sum::<f64>() / n;
    let spread2 = rows.iter().map(|o| (o.value - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let stated2 = rows.iter().map(|o| o.sigma.unwrap_or(0.0).powi(2)).sum::<f64>() / (n * n);
    let mut shared = [0.0; crate::uncertainty::SHARED.len()];
    for (i, s) in shared.iter_mut().enumerate() {
        *s = rows.iter().map(|o| o.shared[i]).sum::<f64>() / n;
    }
    Observation {
        value: mean,
        sigma: rows.iter().any(|o| o.sigma.is_some()).then(|| (stated2 + spread2 / n).sqrt()),
        shared,
        ..rows[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::Units;

    fn row(ti: f64, to: f64, dphi: f64, value: f64, sigma: Option<f64>) -> Observation {
        Observation {
            theta_i: ti.to_radians(),
            theta_o: to.to_radians(),
            dphi: dphi.to_radians(),
            value,
            sigma,
            shared: Default::default(),
        }
    }

    #[test]
    fn grazing_rows_of_a_cosine_file_are_dropped_and_counted() {
        let mut d = Dataset::new(
            Units::FrCos,
            vec![row(30.0, 89.0, 0.0, 1e-3, None), row(30.0, 90.0, 0.0, 5e-4, None)],
        );
        d.settle();
        assert_eq!(d.observations.len(), 1);
        assert!(
            d.warnings[0].starts_with("1 of 2 rows dropped: their θo is beyond 89.9°"),
            "{:?}",
            d.warnings
        );
        // In f_r the row at 90° is a value like any other.
        let mut d = Dataset::new(Units::Fr, vec![row(30.0, 90.0, 0.0, 0.1, None)]);
        d.settle();
        assert_eq!(d.observations.len(), 1);
        assert!(d.warnings.is_empty());
    }

    #[test]
    fn repeats_merge_to_their_mean_with_their_spread() {
        let mut d = Dataset::new(
            Units::Fr,
            vec![
                row(30.0, 20.0, 0.0, 1.0, Some(0.1)),
                row(30.0, 25.0, 0.0, 2.0, Some(0.1)),
                row(30.0, 20.0, 360.0, 3.0, Some(0.1)),
            ],
        );
        let w = d.merge_repeats().unwrap();
        assert!(w.starts_with("1 geometry appears more than once (2 of 3 rows)"), "{w}");
        assert!(w.contains("a factor 3.000"), "{w}");
        assert_eq!(d.observations.len(), 2);
        let m = d.observations[0];
        assert_eq!(m.value, 2.0);
        // Stated: 0.1²·2/4 = 0.005; spread: s² = 2, /n = 1.
        assert!((m.sigma.unwrap() - 1.005f64.sqrt()).abs() < 1e-12);
        assert_eq!(d.observations[1].value, 2.0);
        // Along the normal the azimuth says nothing.
        let mut d = Dataset::new(Units::Fr, vec![row(30.0, 0.0, 0.0, 1.0, None), row(30.0, 0.0, 90.0, 1.0, None)]);
        assert!(d.merge_repeats().unwrap().contains("no uncertainty to add"));
        assert_eq!(d.observations[0].sigma, None);
        let mut d = Dataset::new(Units::Fr, vec![row(30.0, 0.0, 0.0, 1.0, None), row(30.0, 1.0, 0.0, 1.0, None)]);
        assert_eq!(d.merge_repeats(), None);
    }
}
