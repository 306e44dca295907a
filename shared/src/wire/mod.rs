//! The wire format both ends speak below the messages: every frame sealed
//! with a CRC-32 ([`check`]), COBS framing on byte streams ([`framing`]) and
//! postcard-rpc keys matched at the sender's width ([`keys`]). Here, beside
//! the message types, so that the host talks to a head without the firmware
//! crate.

pub mod check;
pub mod framing;
pub mod keys;

pub use keys::key_is;
