//! On-device sanity checks: the models of `models.md` that the head can
//! evaluate for every sample — `lambert`, `retro-phong` and `abc-retro` with
//! the back or view cosine — in Q31.32 fixed point with no floating point on
//! the evaluation path, and the policy that flags a sample whose amplitude
//! disagrees with the model's expectation.

pub mod fixed;
pub mod geometry;
pub mod model;
pub mod policy;

pub use fixed::Fx;
pub use geometry::FixedGeometry;
pub use model::FixedModel;
pub use policy::Sanity;
