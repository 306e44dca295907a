//! The misfit cases: materials a model does not describe (data from one
//! model, or from a material outside every model) and the retro models
//! fitted to them, shared by the `misfit` and `widen` sections.

use gonio_analysis::fit::Dataset;
use gonio_brdf::{Directions, GlassBeads, ModelId};
use gonio_tests::synthetic;
use std::rc::Rc;

use crate::NOISE;

/// A material the cases are generated from.
struct Generator {
    name: &'static str,
    brdf: Box<dyn Fn(&Directions) -> f64>,
    /// The model it is, if any (not fitted to its own data).
    model: Option<ModelId>,
}

fn generators() -> Vec<Generator> {
    let model = |m: ModelId| {
        let mat = synthetic::reference(m);
        Generator {
            name: m.name(),
            brdf: Box::new(move |d| mat.eval(d)),
            model: Some(m),
        }
    };
    let beads = GlassBeads::default();
    vec![
        Generator {
            name: "glass-beads",
            brdf: Box::new(move |d| beads.eval(d)),
            model: None,
        },
        Generator {
            name: "two-lobes",
            brdf: Box::new(synthetic::two_lobes),
            model: None,
        },
        model(ModelId::RetroPhong),
        model(ModelId::AbcRetro),
        model(ModelId::Lafortune),
    ]
}

const RETRO_MODELS: [ModelId; 6] = [
    ModelId::RetroPhong,
    ModelId::AbcRetro,
    ModelId::AbcRetroPerLobe,
    ModelId::BeckmannRetro,
    ModelId::BlinnRetro,
    ModelId::Lafortune,
];

/// One model fitted to one material's samples.
pub struct Case {
    pub samples: usize,
    pub material: &'static str,
    pub model: ModelId,
    pub data: Rc<Dataset>,
}

impl Case {
    /// `SAMPLES/MATERIAL/MODEL`, what a filter is matched against.
    pub fn label(&self) -> String {
        format!("{}/{}/{}", self.samples, self.material, self.model.name())
    }
}

/// One material's noisy samples.
pub struct Samples {
    pub samples: usize,
    pub material: &'static str,
    /// The model it is, if any.
    pub model: Option<ModelId>,
    pub data: Rc<Dataset>,
}

/// Every material's samples, 2 % noise, at 7 000 samples, and at 80 000
/// those outside every model (the peers take minutes per case there).
pub fn materials() -> Vec<Samples> {
    let mut out = Vec::new();
    for (samples, geos) in [(7000, synthetic::belcour_geometries()), (80_000, synthetic::dense_geometries())] {
        for g in generators() {
            if samples > 7000 && g.model.is_some() {
                continue;
            }
            out.push(Samples {
                samples,
                material: g.name,
                model: g.model,
                data: Rc::new(synthetic::samples_of(&g.brdf, &geos, samples, NOISE, 11)),
            });
        }
    }
    out
}

/// Every material fitted by every retro model but its own; at 80 000
/// samples only the models the papers argue over.
pub fn cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for m in materials() {
        for model in RETRO_MODELS {
            if Some(model) == m.model || (m.samples > 7000 && matches!(model, ModelId::BeckmannRetro | ModelId::BlinnRetro)) {
                continue;
            }
            cases.push(Case {
                samples: m.samples,
                material: m.material,
                model,
                data: m.data.clone(),
            });
        }
    }
    cases
}
