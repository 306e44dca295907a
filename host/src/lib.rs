//! The host side of the gonioreflectometer: the `gonio` tool's library.
//!
//! [`client`] talks to a head (real, or simulated in [`sim`]) over the
//! transports in [`link`]; [`scan`] runs scans and [`samples_csv`] /
//! [`run_record`] store them, planned by [`scan_order`]; [`brdf`] holds the
//! models of `docs/models.md`; [`operator`] is where the library's notices
//! and progress bars go (the library never prints itself).

pub mod brdf;
pub mod calibration;
pub mod cli;
pub mod client;
pub mod coefficients;
pub mod fit;
pub mod formats;
pub mod link;
pub mod operator;
pub mod plot;
pub mod report;
pub mod run_record;
pub mod samples_csv;
pub mod scan;
pub mod scan_dir;
pub mod scan_order;
pub mod session;
pub mod sim;
pub mod uncertainty;
pub mod usb;
