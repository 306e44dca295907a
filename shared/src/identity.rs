//! Who is on the other end of the link.

use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// Bumped on every change of a message type, of a name on the wire or of
/// what a message means (what each bump changed is in git's history; a
/// sweep scan's layout dates from [`crate::scan::SWEEP_LAYOUT_SINCE`]). Keys
/// are schema-hashed too, so an old head answers new requests with
/// `UnknownKey`; the identify endpoint keeps its types stable so the host
/// can always tell *why*.
pub const PROTOCOL_VERSION: u16 = 18;

/// USB identity of the head (pid.codes test range until a PID is assigned).
pub const USB_VID: u16 = 0x1209;
pub const USB_PID: u16 = 0x0001;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Identity {
    pub protocol_version: u16,
    pub firmware_version: heapless::String<16>,
    pub board: heapless::String<32>,
    pub serial: heapless::String<24>,
    /// True for the simulated head: the only way the host can tell it apart.
    pub simulated: bool,
    pub capabilities: Capabilities,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Capabilities {
    pub axes: u8,
    /// Number of switchable transimpedance gains.
    pub gain_ranges: u8,
    pub adc_bits: u8,
    /// Largest number of incidence angles in one scan request.
    pub max_scan_incidences: u8,
    /// Transimpedance gains (V/A), lowest first.
    pub gains_v_per_a: [f32; 4],
}
