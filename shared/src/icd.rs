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

endpoints! {
    list = ENDPOINT_LIST;
    | EndpointTy            | RequestTy         | ResponseTy              | Path                 |
    | ----------            | ---------         | ----------              | ----                 |
    | IdentifyEndpoint      | ()                | Identity                | "gonio/identify"     |
    | StatusEndpoint        | ()                | Status                  | "gonio/status"       |
    | MechanicsEndpoint     | ()                | Mechanics               | "gonio/mechanics"    |
    | HomeEndpoint          | HomeRequest       | HomeReply               | "gonio/home"         |
    | MoveEndpoint          | Geometry          | MoveReply               | "gonio/move"         |
    | MeasureEndpoint       | MeasureRequest    | MeasureReply            | "gonio/measure"      |
    | ScanEndpoint          | ScanSpec          | ScanReply               | "gonio/scan"         |
    | AbortEndpoint         | ()                | Status                  | "gonio/abort"        |
    | DetectionEndpoint     | DetectionSettings | DetectionReply          | "gonio/detection"    |
    | SanityEndpoint        | SanityConfig      | SanityReply             | "gonio/sanity"       |
    | CalibrateEndpoint     | CalibrateRequest  | CalibrateReply          | "gonio/calibrate"    |
    | SafetyEndpoint        | SafetySettings    | SafetyReply             | "gonio/safety"       |
    | PauseEndpoint         | ()                | PauseReply              | "gonio/pause"        |
    | ContinueEndpoint      | ()                | ContinueReply           | "gonio/continue"     |
    | PlanEndpoint          | PlanChunk         | PlanReply               | "gonio/plan"         |
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
