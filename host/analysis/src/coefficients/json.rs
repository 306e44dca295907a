//! Coefficients as one JSON object, as `gonio coefficients --json` prints
//! them and `gonio demo` keeps them.

use super::{Coefficient, Kind};
use crate::instrument::Instrument;
use serde_json::{json, Value};

/// The coefficients as JSON: `ra` (a list) and `rl` (the last R_L, or
/// null), with the instrument the values rest on (`None`: a model's).
pub fn to_json(values: &[Coefficient], instrument: Option<Instrument>) -> Value {
    let entry = |c: &Coefficient| {
        let g = &c.request.geometry;
        let mut v = json!({
            "alpha_deg": g.alpha_deg, "beta_deg": g.beta_deg(), "epsilon_deg": g.epsilon_deg,
            "value": c.estimate.value, "u": c.estimate.u,
            "theta_i_deg": c.sample_angles_deg[0], "theta_o_deg": c.sample_angles_deg[1], "dphi_deg": c.sample_angles_deg[2],
            "source_aperture_deg": c.request.apertures.source_deg, "receiver_aperture_deg": c.request.apertures.receiver_deg,
        });
        if g.beta2_deg != 0.0 {
            v["beta1_deg"] = json!(g.beta1_deg);
            v["beta2_deg"] = json!(g.beta2_deg);
        }
        if !c.estimate.nearest.is_empty() {
            v["nearest"] = json!(c.estimate.nearest);
        }
        let e = &c.estimate;
        if let Some(b) = &e.basis {
            v["provenance"] = json!(b.provenance);
            v["basis"] = json!(b.why);
            if let Some(m) = &b.measure {
                v["measure_with"] = json!(m);
            }
        }
        for (key, part) in [
            ("u_params", e.u_params),
            ("u_model", e.u_model),
            ("u_aperture", e.u_aperture),
            ("u_arm_zero", e.u_arm_zero),
        ] {
            if let Some(x) = part {
                v[key] = json!(x);
            }
        }
        if let Some(m) = e.model {
            v["model"] = json!(m);
            v["models"] = json!(e.models);
        }
        v
    };
    let ra: Vec<Value> = values.iter().filter(|c| c.request.kind == Kind::Ra).map(entry).collect();
    let rl = values.iter().rev().find(|c| c.request.kind == Kind::Rl).map(|c| {
        let mut v = entry(c);
        if let Some(o) = v.as_object_mut() {
            o.remove("epsilon_deg");
        }
        v
    });
    json!({
        "ra": ra, "rl": rl,
        "units": {"ra": Kind::Ra.unit(), "rl": Kind::Rl.unit()},
        "wavelength_nm": instrument.and_then(|i| i.wavelength_nm()),
        "instrument": instrument.map(|i| i.to_json()),
        "note": format!("spectral values at {}, not photometric; u is the standard uncertainty (k = 1); \
                 provenance: measured (a sample at the geometry), interpolated (between samples on every side within the \
                 standard's aperture), extrapolated (within the data's spacing, an adequate model carries it: u holds the \
                 adequate models' spread, u_model) or not measured (value null: the basis says why, measure_with the scan \
                 that would measure it)", instrument.map_or("no instrument's wavelength (a model)".into(), |i| i.wavelength_text())),
    })
}
