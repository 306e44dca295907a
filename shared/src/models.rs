//! The table of the model contract (`docs/models.md` §2): every model's id
//! and its parameter names in order, which also gives its arity. The host's
//! f64 catalog, the head's fixed-point sanity models, the BRDF Explorer
//! export and the Python peer of `fit-bench` all take their names and order
//! from here; `tests/tests/model_contract.rs` holds `docs/models.md` and the
//! Python peer to it.

/// One row of the table.
#[derive(Debug, PartialEq, Eq)]
pub struct ModelSpec {
    /// The id of the CLI, JSON and file names (kebab-case).
    pub id: &'static str,
    /// Parameter names in the order every parameter vector uses.
    pub params: &'static [&'static str],
}

impl ModelSpec {
    pub const fn arity(&self) -> usize {
        self.params.len()
    }
}

pub const LAMBERT: ModelSpec = ModelSpec {
    id: "lambert",
    params: &["kd"],
};
pub const RETRO_PHONG: ModelSpec = ModelSpec {
    id: "retro-phong",
    params: &["kd", "n", "k1", "k2", "k3", "k4"],
};
pub const ABC_RETRO: ModelSpec = ModelSpec {
    id: "abc-retro",
    params: &["kd", "r0", "ab", "bb", "cb", "ar", "br", "cr"],
};
/// `abc-retro` with a Fresnel `r0` of each lobe's own (Belcour §4.C; ALTA's
/// retro tutorial fits this form).
pub const ABC_RETRO_PER_LOBE: ModelSpec = ModelSpec {
    id: "abc-retro-per-lobe",
    params: &["kd", "r0_b", "ab", "bb", "cb", "r0_r", "ar", "br", "cr"],
};
pub const BECKMANN_RETRO: ModelSpec = ModelSpec {
    id: "beckmann-retro",
    params: &["kd", "alpha", "r0"],
};
pub const BLINN_RETRO: ModelSpec = ModelSpec {
    id: "blinn-retro",
    params: &["kd", "alpha_r", "alpha_b"],
};
pub const LAFORTUNE: ModelSpec = ModelSpec {
    id: "lafortune",
    params: &["kd", "cxy_s", "cz_s", "n_s", "cxy_r", "cz_r", "n_r"],
};
pub const OREN_NAYAR: ModelSpec = ModelSpec {
    id: "oren-nayar",
    params: &["rho", "sigma"],
};
pub const FIVE_PARAM: ModelSpec = ModelSpec {
    id: "five-param",
    params: &["kb", "kr", "a", "b", "kd"],
};

/// Every model, in the order of `docs/models.md` §2.
pub const MODELS: [&ModelSpec; 9] = [
    &LAMBERT,
    &RETRO_PHONG,
    &ABC_RETRO,
    &ABC_RETRO_PER_LOBE,
    &BECKMANN_RETRO,
    &BLINN_RETRO,
    &LAFORTUNE,
    &OREN_NAYAR,
    &FIVE_PARAM,
];
