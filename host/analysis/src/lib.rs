//! Analysis of stored scans: what a scan directory's files (`gonio-scan-dir`)
//! hold, turned into BRDF values and what a physicist reads of them. Reads
//! files only: links no tokio and no serial port.
//!
//! [`calibration`] scales raw samples by the reference plate, with each
//! value's budget from [`uncertainty`]; [`fit`] fits the models of
//! `gonio-brdf` (`docs/models.md`); [`coefficients`] gives R_A and R_L with
//! what each rests on, and [`instrument`] what measured the data; [`evaluation`]
//! evaluates one BRDF at a geometry and over the hemisphere; [`formats`] reads and writes other tools' files;
//! [`plot`] and [`report`] draw and tabulate; [`lobe`] places the points a
//! narrow lobe needs; [`moments`] measures a retro lobe's shape;
//! [`rational`] fits the non-parametric rational model through the data's
//! intervals.

pub mod calibration;
pub mod coefficients;
pub mod evaluation;
pub mod fit;
pub mod formats;
pub mod instrument;
pub mod lobe;
pub mod moments;
pub mod plot;
pub mod rational;
pub mod render;
pub mod repeatability;
pub mod report;
pub mod rounding;
pub mod uncertainty;
