//! Acquisition from a head: everything that talks to one, and nothing that
//! analyses what it measured.
//!
//! [`grid`] checks the grid a user asks for; [`client`] talks to a head at a [`target`] (a port, or a head the caller
//! builds: the `gonio` tool wires the simulated head in) over the transports
//! in [`link`] ([`usb`] lists heads on the bus); [`session`] sets the
//! detector up and keeps the link alive; [`plate`] measures the reference
//! plate; [`scan`] runs a scan in the order [`scan_order`] plans and stores
//! it through `gonio-scan-dir`; [`operator`] is where notices and progress
//! bars go (the library never prints itself), and [`interrupt`] how the
//! operator's Ctrl-C stops a scan.

pub mod client;
pub mod grid;
pub mod interrupt;
pub mod link;
pub mod operator;
pub mod plate;
pub mod scan;
pub mod scan_order;
pub mod session;
pub mod target;
pub mod usb;
