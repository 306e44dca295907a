//! What the head is doing, for the host's status display and health checks.

use crate::detection::DetectionSettings;
use crate::fault::Fault;
use crate::geometry::AxisAngles;
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HeadState {
    Idle,
    Homing,
    Moving,
    /// A measurement or the reference learned.
    Measuring,
    /// A scan is running; `next_order` is the next point to visit.
    Scanning {
        next_order: u32,
        total: u32,
    },
    /// Scan `run` is held at `next_order`; `gonio/continue` carries it on there.
    Paused {
        run: u32,
        next_order: u32,
        total: u32,
    },
    /// The motion decelerates after a stop (the laser is already off).
    Stopping,
    /// E-STOP: refused until the input is closed and the host continues.
    Faulted,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    pub state: HeadState,
    pub homed: bool,
    pub laser_on: bool,
    /// The motor drivers are enabled; when not, the motors hold by detent
    /// (and the worm gears) only, and are enabled again at the next move.
    pub drivers_enabled: bool,
    /// The E-STOP input reads open.
    pub estop_open: bool,
    pub axes: AxisAngles,
    pub detection: DetectionSettings,
    pub samples_sent: u32,
    pub samples_flagged: u32,
    pub samples_remeasured: u32,
    pub sanity_loaded: bool,
    pub last_fault: Option<Fault>,
    /// Why the laser may not come on until the head restarts (a crystal
    /// that failed its check, E601; the `no-laser` image, E604), if so:
    /// beside `last_fault`, which keeps why the head last restarted.
    pub laser_inhibited: Option<Fault>,
    pub uptime_us: u64,
    /// Requests received and kept unanswered while an operation or a scan
    /// point runs (answered when it ends). With none kept, a request the
    /// host sent before this poll that is not the running operation's own
    /// was lost on the link.
    pub requests_held: u8,
}
