//! Measured BRDF values as the fitting engine sees them, whatever file they
//! came from: geometry in radians, a value in the file's units, and an
//! optional standard uncertainty.

use crate::instrument::Instrument;
use crate::uncertainty::SHARED;
use anyhow::{bail, Result};
use gonio_brdf::{Directions, GeometryTerms};
use serde::{Deserialize, Serialize};

/// Units of a value (`models.md` §1, ALTA's `#PARAM_OUT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Units {
    /// `f_r` in sr⁻¹ (`INV_STERADIAN`).
    Fr,
    /// `f_r·cosθo` in sr⁻¹ (`INV_STERADIAN_COSINE_FACTOR`).
    FrCos,
}

impl Units {
    /// The quantity and its unit, for people.
    pub fn label(self) -> &'static str {
        match self {
            Units::Fr => "f_r, sr⁻¹",
            Units::FrCos => "f_r·cosθo, sr⁻¹",
        }
    }
}

/// One measured value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    pub theta_i: f64,
    pub theta_o: f64,
    pub dphi: f64,
    pub value: f64,
    pub sigma: Option<f64>,
    /// How much `value` moves when each input shared by the whole data set
    /// (`uncertainty::SHARED`) is off by one standard uncertainty; zeros
    /// where the source says nothing of them.
    pub shared: [f64; SHARED.len()],
}

/// Refuses angles no measurement has (radians): incidence and view in the
/// sample's front hemisphere, [0°, 90°], and Δφ within [−360°, 360°]; gives
/// them back with what lies within [`ANGLE_SLACK`] of the hemisphere
/// brought into it. What a reader says of a row it cannot take; the file's
/// own words are its caller's (line numbers).
pub fn check_angles(theta_i: f64, theta_o: f64, dphi: f64) -> Result<(f64, f64, f64), String> {
    let front = |t: f64| (-ANGLE_SLACK..=std::f64::consts::FRAC_PI_2 + ANGLE_SLACK).contains(&t);
    let deg = |x: f64| format!("{}°", (x.to_degrees() * 1e4).round() / 1e4);
    if !front(theta_i) {
        return Err(format!("θi = {} is not an incidence angle (0° to 90°)", deg(theta_i)));
    }
    if !front(theta_o) {
        return Err(format!("θo = {} is not a view angle (0° to 90°)", deg(theta_o)));
    }
    if dphi.abs() > 2.0 * std::f64::consts::PI + ANGLE_SLACK {
        return Err(format!("Δφ = {} is outside −360° to 360°", deg(dphi)));
    }
    let hemisphere = |t: f64| t.clamp(0.0, std::f64::consts::FRAC_PI_2);
    Ok((hemisphere(theta_i), hemisphere(theta_o), dphi))
}

/// Beyond this view angle (degrees) a value stored as `f_r·cosθo` is not
/// turned into `f_r`: cosθo < 0.0018 would multiply its value, and its
/// noise, by more than 570. Measured tapes store rows at θo = 90°, where
/// cos 90° = 6·10⁻¹⁷ in floating point made `f_r` ≈ 10¹³; readers drop
/// them (`settle.rs`). The head's own most grazing view (EN 1436's
/// θo = 87.71°) is well inside it.
pub const GRAZING_DEG: f64 = 89.9;

/// How far beyond the hemisphere an angle may be written (radians, 0.006°):
/// files print radians rounded, 90° as `1.5708` is 4·10⁻⁶ beyond it, and a
/// direction computed on the horizon may land a rounding off it.
pub const ANGLE_SLACK: f64 = 1e-4;

impl Observation {
    pub fn directions(&self) -> Directions {
        Directions::from_angles(self.theta_i, self.theta_o, self.dphi)
    }

    pub fn geometry(&self) -> GeometryTerms {
        GeometryTerms::new(&self.directions())
    }

    /// The factor from `f_r` to `units`.
    pub fn unit_factor(&self, units: Units) -> f64 {
        match units {
            Units::Fr => 1.0,
            Units::FrCos => self.theta_o.cos(),
        }
    }

    /// Whether its value in `units` cannot give `f_r`: `f_r·cosθo` beyond
    /// [`GRAZING_DEG`].
    pub fn too_grazing_for(&self, units: Units) -> bool {
        units == Units::FrCos && self.theta_o.to_degrees() > GRAZING_DEG
    }

    /// In the retro half-space `cosΔφ ≥ 0` (`Δφ = 0` is the retro half-plane).
    pub fn on_retro_side(&self) -> bool {
        self.dphi.cos() >= 0.0
    }
}

/// A set of observations in one unit.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    pub units: Units,
    pub observations: Vec<Observation>,
    /// Header lines of the source kept as metadata (ALTA comments, …).
    pub metadata: Vec<String>,
    /// False where the source did not say what its values are (ALTA's
    /// `UNKNOWN_OUTPUT`): `units` is then an assumption, which `--units`
    /// replaces.
    pub units_stated: bool,
    /// What the reader assumed or found doubtful, for the user.
    pub warnings: Vec<String>,
    /// What measured the values: this head, or another instrument whose
    /// apertures and wavelength are stated or not known.
    pub instrument: Instrument,
}

/// Whether `theta` (rad) is one of `list` (degrees), within 0.05°.
pub fn theta_in(theta: f64, list_deg: &[f64]) -> bool {
    list_deg.iter().any(|t| (theta.to_degrees() - t).abs() < 0.05)
}

impl Dataset {
    /// Observations in `units` that say what they are, with no metadata,
    /// no warning, and an instrument not known (a test's, a simulation's).
    pub fn new(units: Units, observations: Vec<Observation>) -> Dataset {
        Dataset {
            units,
            observations,
            metadata: Vec::new(),
            units_stated: true,
            warnings: Vec::new(),
            instrument: Instrument::Unknown,
        }
    }

    /// The same values in other units.
    pub fn in_units(&self, units: Units) -> Result<Dataset> {
        let mut out = self.clone();
        out.units = units;
        for o in &mut out.observations {
            if o.too_grazing_for(self.units) {
                bail!(
                    "θo = {:.3}° is beyond {GRAZING_DEG}°: its f_r·cosθo cannot give f_r",
                    o.theta_o.to_degrees()
                );
            }
            let k = o.unit_factor(units) / o.unit_factor(self.units);
            o.value *= k;
            o.sigma = o.sigma.map(|s| s * k);
            o.shared = o.shared.map(|s| s * k);
        }
        Ok(out)
    }

    /// Keeps the observations `keep` accepts.
    pub fn filter(&self, keep: impl Fn(&Observation) -> bool) -> Dataset {
        Dataset {
            observations: self.observations.iter().copied().filter(|o| keep(o)).collect(),
            ..self.clone()
        }
    }

    /// What makes the data doubtful as a fitting input, for a warning:
    /// negative values, every value zero, a single incidence angle.
    pub fn doubts(&self) -> Vec<String> {
        let mut out = Vec::new();
        let n = self.observations.len();
        let negative = self.observations.iter().filter(|o| o.value < 0.0).count();
        if negative > 0 {
            out.push(format!(
                "{negative} of {n} values are negative (noise about zero, or an offset?), where a BRDF cannot be: they are fitted as they are"
            ));
        }
        if n > 0 && self.observations.iter().all(|o| o.value == 0.0) {
            out.push("every value is zero".into());
        }
        if let [one] = self.incidence_angles_deg()[..] {
            out.push(format!(
                "one incidence angle only (θi = {one}°): how the BRDF changes with θi is not measured, and a fit extrapolates it"
            ));
        }
        out
    }

    /// The distinct incidence angles, in degrees, rounded to 0.01°.
    pub fn incidence_angles_deg(&self) -> Vec<f64> {
        let mut t: Vec<f64> = self
            .observations
            .iter()
            .map(|o| (o.theta_i.to_degrees() * 100.0).round() / 100.0)
            .collect();
        t.sort_by(f64::total_cmp);
        t.dedup();
        t
    }
}
