//! A sweep under way (`run.rs` runs it): what a scan keeps of it between
//! two of the serve loop's turns.

use crate::motion::Running;
use gonio_shared::sample::ScanPosition;

/// A sweep under way, between two of its samples: its move in flight and
/// where the next sample begins (the design of its samples is the
/// detector's). A scan keeps it
/// across the serve loop's turns (one sample each).
pub(crate) struct Sweeping {
    pub(crate) run: Running,
    /// The sweep scan's row, if it is one.
    pub(crate) scan: Option<ScanPosition>,
    /// When the move started (µs).
    pub(crate) t0: u64,
    /// Steps emitted and head time where the next sample begins.
    pub(crate) first: [u32; 3],
    pub(crate) start_us: u64,
    /// False once the move is over (its last sample taken).
    pub(crate) moving: bool,
    /// The detector sees through the beam splitter all along (a path
    /// cannot cross the blind zone between it and the open view,
    /// [`super::check_path`]).
    pub(crate) splitter: bool,
    /// Some sample so far rose above the noise.
    pub(crate) lit: bool,
    pub(crate) samples: u32,
}
