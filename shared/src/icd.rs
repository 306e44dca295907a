//! Endpoints and topics: paths and schema-hashed keys (postcard-rpc).
//!
//! Requests are answered in order; a scan is accepted at once, its visit
//! order follows in chunks on [`PlanEndpoint`] (the host plans it), and its
//! points arrive on [`ScanEventTopic`] while the head still answers
//! [`StatusEndpoint`], [`PlanEndpoint`] and [`AbortEndpoint`]. Wire-level errors (unknown key, undecodable body)
//! come back on postcard-rpc's standard error path,
//! [`postcard_rpc::standard_icd::ERROR_PATH`].

use crate::detection::{CalibrateRequest, CalibrationReport, DetectionReport, DetectionSettings};
use crate::fault::Fault;
use crate::geometry::{AxisAngles, Geometry};
use crate::identity::Identity;
use crate::mechanics::Mechanics;
use crate::safety::SafetySettings;
use crate::sample::Sample;
use crate::sanity::SanityConfig;
use crate::scan::{PlanChunk, PlanQueued, ScanAccepted, ScanEvent, ScanSpec};
use crate::status::Status;
use crate::Reply;
use postcard_rpc::{endpoints, topics, TopicDirection};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// Which axes to home.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HomeRequest {
    pub rotation: bool,
    pub cradle: bool,
    pub arm: bool,
}

impl HomeRequest {
    pub const ALL: HomeRequest = HomeRequest {
        rotation: true,
        cradle: true,
        arm: true,
    };
}

/// Where a move ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MoveReport {
    pub reached: Geometry,
    pub axes: AxisAngles,
    /// Time the move took (s).
    pub duration_s: f32,
}

/// Measure one point, after moving there when a geometry is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MeasureRequest {
    pub at: Option<Geometry>,
}

// The endpoint table takes plain type names, so each reply type is named here.
pub type HomeReply = Reply<AxisAngles>;
pub type MoveReply = Reply<MoveReport>;
pub type MeasureReply = Reply<Sample>;
pub type ScanReply = Reply<ScanAccepted>;
pub type DetectionReply = Reply<DetectionReport>;
pub type SanityReply = Reply<()>;
pub type CalibrateReply = Reply<CalibrationReport>;
pub type SafetyReply = Reply<()>;
pub type PauseReply = Reply<Status>;
pub type ContinueReply = Reply<Status>;
pub type PlanReply = Reply<PlanQueued>;

/// The one table of the head's endpoints: the command each carries, its
/// marker type, request, response and path. It makes postcard-rpc's
/// endpoints (keys, schemas, [`ENDPOINT_LIST`]) and [`for_each_endpoint!`],
/// which hands the commands to code generated per endpoint (the firmware's
/// `Command` and `decode`). A new endpoint is a row here and its arm in the
/// firmware's `handle` (which the compiler asks for), plus the host client's
/// typed method; the firmware's `dispatch.rs` imports its request type, as
/// the generated code names request types as the caller sees them. Each
/// type is one token (postcard-rpc's table takes no paths or generics): a
/// reply type is an alias above.
macro_rules! head_endpoints {
    (
        $d:tt
        | Command | EndpointTy | RequestTy | ResponseTy | Path |
        | $(-)* | $(-)* | $(-)* | $(-)* | $(-)* |
        $( | $cmd:ident | $ep:ident | $req:tt | $resp:tt | $path:literal | )*
    ) => {
        endpoints! {
            list = ENDPOINT_LIST;
            | EndpointTy | RequestTy | ResponseTy | Path |
            | ---------- | --------- | ---------- | ---- |
            $( | $ep | $req | $resp | $path | )*
        }

        /// Calls `$m! { Command(Request) = Endpoint, ... }` with every
        /// endpoint of the head, from the one table in `icd.rs` (the request
        /// types are named as the caller imports them).
        #[macro_export]
        macro_rules! for_each_endpoint {
            ($d m:ident) => {
                $d m! { $( $cmd($req) = $d crate::icd::$ep, )* }
            };
        }
    };
}

head_endpoints! {
    $
    | Command    | EndpointTy            | RequestTy         | ResponseTy              | Path                 |
    | -------    | ----------            | ---------         | ----------              | ----                 |
    | Identify   | IdentifyEndpoint      | ()                | Identity                | "gonio/identify"     |
    | Status     | StatusEndpoint        | ()                | Status                  | "gonio/status"       |
    | Mechanics  | MechanicsEndpoint     | ()                | Mechanics               | "gonio/mechanics"    |
    | Home       | HomeEndpoint          | HomeRequest       | HomeReply               | "gonio/home"         |
    | Move       | MoveEndpoint          | Geometry          | MoveReply               | "gonio/move"         |
    | Measure    | MeasureEndpoint       | MeasureRequest    | MeasureReply            | "gonio/measure"      |
    | Scan       | ScanEndpoint          | ScanSpec          | ScanReply               | "gonio/scan"         |
    | Abort      | AbortEndpoint         | ()                | Status                  | "gonio/abort"        |
    | Detection  | DetectionEndpoint     | DetectionSettings | DetectionReply          | "gonio/detection"    |
    | Sanity     | SanityEndpoint        | SanityConfig      | SanityReply             | "gonio/sanity"       |
    | Calibrate  | CalibrateEndpoint     | CalibrateRequest  | CalibrateReply          | "gonio/calibrate"    |
    | Safety     | SafetyEndpoint        | SafetySettings    | SafetyReply             | "gonio/safety"       |
    | Pause      | PauseEndpoint         | ()                | PauseReply              | "gonio/pause"        |
    | Continue   | ContinueEndpoint      | ()                | ContinueReply           | "gonio/continue"     |
    | Plan       | PlanEndpoint          | PlanChunk         | PlanReply               | "gonio/plan"         |
}

topics! {
    list = TOPICS_OUT_LIST;
    direction = TopicDirection::ToClient;
    | TopicTy               | MessageTy         | Path                 |
    | -------               | ---------         | ----                 |
    | ScanEventTopic        | ScanEvent         | "gonio/scan/event"   |
    | FaultTopic            | Fault             | "gonio/fault"        |
}

topics! {
    list = TOPICS_IN_LIST;
    direction = TopicDirection::ToServer;
    | TopicTy               | MessageTy         | Path                 |
    | -------               | ---------         | ----                 |
}
