//! The non-parametric model of Belcour et al. 2014 (§5.B, Table 1): a
//! rational function through the *vertical segments* of the data
//! (Pacanowski et al. 2012, "Rational BRDF"), times a cosine factor or not.
//! Where a parametric model is fitted in the least-squares sense, this one
//! is the least-norm function that stays within every sample's interval:
//! with `--segments sigma` the measurement's own k = 2 uncertainty, so that
//! the function fits within what was measured, or says which sample no
//! function of the allowed terms can reach.
//!
//! `basis` the Legendre terms and the coordinates' box, `segments` the
//! intervals, `qp` one count's quadratic programme, `active_set` its
//! solver (Goldfarb–Idnani), `search` the walk over counts of terms,
//! `programmes` what it walks over in both coordinate systems, `fit` the
//! fit it gives, `function` the result as a BRDF, `file` its JSON, `text` its words.

pub mod active_set;
pub mod basis;
pub mod file;
pub mod fit;
pub mod function;
pub mod programmes;
pub mod qp;
pub mod search;
pub mod segments;
pub mod text;

pub use fit::{fit, fit_observed, RationalFit, RationalSpec};
pub use function::Rational;
pub use programmes::{grazing, Attempt, Held};
pub use segments::SegmentSource;
