//! The geometries a user asks for, as named sets or an α × β × ε grid,
//! through apertures of the user's or each set's own.

use super::{grid, Apertures, Request, Set, ASTM_APERTURES};
use anyhow::{bail, Result};

/// What `gonio coefficients` asks for, in degrees.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Asked {
    pub sets: Vec<Set>,
    /// R_L at the 30 m road-marking geometry too (as [`Set::En1436`]).
    pub rl: bool,
    /// R_A at every α × β × ε (β coplanar), with ASTM's apertures.
    pub alpha_deg: Vec<f64>,
    pub beta_deg: Vec<f64>,
    pub epsilon_deg: Vec<f64>,
    /// Apertures replacing each request's own (angular diameters, degrees).
    pub source_aperture_deg: Option<f64>,
    pub receiver_aperture_deg: Option<f64>,
}

impl Asked {
    /// The requests, in the order asked; an empty ask is refused.
    pub fn requests(&self) -> Result<Vec<Request>> {
        let mut out: Vec<Request> = self.sets.iter().flat_map(|s| s.requests()).collect();
        if self.rl {
            out.extend(Set::En1436.requests());
        }
        match (self.alpha_deg.is_empty(), self.beta_deg.is_empty()) {
            (false, false) => out.extend(grid(&self.alpha_deg, &self.beta_deg, &self.epsilon_deg, ASTM_APERTURES)),
            (true, true) => {}
            _ => bail!("--alpha and --beta go together"),
        }
        if out.is_empty() {
            bail!("no geometry: give --set astm-e810, --set en1436, --rl, or --alpha with --beta");
        }
        for r in &mut out {
            r.apertures = Apertures {
                source_deg: self.source_aperture_deg.unwrap_or(r.apertures.source_deg),
                receiver_deg: self.receiver_aperture_deg.unwrap_or(r.apertures.receiver_deg),
            };
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_ask_lists_its_sets_then_its_grid_through_the_apertures_given() {
        let a = Asked {
            sets: vec![Set::En1436],
            alpha_deg: vec![0.2, 0.33],
            beta_deg: vec![5.0],
            epsilon_deg: vec![0.0],
            receiver_aperture_deg: Some(0.1),
            ..Asked::default()
        };
        let r = a.requests().unwrap();
        assert_eq!(r.len(), 3);
        let en = Set::En1436.requests()[0];
        assert_eq!((r[0].kind, r[0].geometry), (en.kind, en.geometry));
        assert_eq!(r[0].apertures.source_deg, en.apertures.source_deg);
        assert!(r.iter().all(|r| r.apertures.receiver_deg == 0.1));
        assert!(Asked::default().requests().unwrap_err().to_string().contains("no geometry"));
        let half = Asked {
            alpha_deg: vec![0.2],
            ..Asked::default()
        };
        assert!(half.requests().unwrap_err().to_string().contains("go together"));
    }
}
