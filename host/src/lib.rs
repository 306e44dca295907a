//! The host side of the gonioreflectometer: the `gonio` tool's library.
//!
//! [`client`] talks to a head at a [`target`] (a port, or a head the caller
//! builds: `cli/` wires the simulated head of `gonio-sim` in) over the
//! transports in [`link`]; [`scan`] runs scans and [`samples_csv`] /
//! [`run_record`] store them, planned by [`scan_order`]; [`fit`] fits the
//! models of `gonio-brdf` (`docs/models.md`); [`operator`] is where the
//! library's notices and progress bars go (the library never prints itself).

pub mod calibration;
pub mod cli;
pub mod client;
pub mod coefficients;
pub mod fit;
pub mod formats;
pub mod link;
pub mod lobe;
pub mod operator;
pub mod plot;
pub mod report;
pub mod run_record;
pub mod samples_csv;
pub mod scan;
pub mod scan_dir;
pub mod scan_order;
pub mod session;
pub mod swept;
pub mod target;
pub mod uncertainty;
pub mod usb;
