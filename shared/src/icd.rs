//! Endpoints and topics: paths and schema-hashed keys (postcard-rpc).
//!
//! Requests are answered in order; a scan is accepted at once, its visit
//! order follows in chunks on [`VisitEndpoint`] (the host plans it), and its
//! points arrive on [`ScanEventTopic`] while the head still answers
//! [`StatusEndpoint`], [`VisitEndpoint`] and [`AbortEndpoint`]. Wire-level errors (unknown key, undecodable body)
//! come back on postcard-rpc's standard error path,
//! [`postcard_rpc::standard_icd::ERROR_PATH`].

use crate::detection::{DetectionReport, DetectionSettings, LearnReport, LearnRequest};
use crate::fault::Fault;
use crate::geometry::{AxisAngles, Geometry};
use crate::identity::Identity;
use crate::mechanics::Mechanics;
use crate::safety::SafetySettings;
use crate::sample::Sample;
use crate::sanity::SanityConfig;
use crate::scan::{ScanAccepted, ScanEvent, ScanSpec, VisitChunk, VisitsQueued};
use crate::status::Status;
use crate::Reply;
use postcard_rpc::{endpoints, topics, Endpoint, TopicDirection};
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

/// How long the head may take to answer a request, a promise of its serve
/// loop: the host's timeout for each request follows from it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Latency {
    /// Answered at once: settings, status, abort, a scan's acceptance.
    Prompt,
    /// Answered after a move, a measured point or the reference learned: seconds,
    /// a minute or two for the longest move.
    Motion,
    /// Answered once every axis has homed: minutes.
    Homing,
}

/// An endpoint of the head's table, with how long its answer may take.
pub trait HeadEndpoint: Endpoint {
    const LATENCY: Latency;
}

/// What a request's answer says: accepted, with what it carries, or refused
/// with a [`Fault`]. Requests that cannot be refused answer with their value.
pub trait Answer {
    type Accepted;
    fn accepted(self) -> Reply<Self::Accepted>;
}

impl<T> Answer for Reply<T> {
    type Accepted = T;
    fn accepted(self) -> Reply<T> {
        self
    }
}

/// Answers that cannot be a refusal.
macro_rules! always_accepted {
    ($($t:ty),*) => {$(
        impl Answer for $t {
            type Accepted = $t;
            fn accepted(self) -> Reply<$t> {
                Ok(self)
            }
        }
    )*};
}
always_accepted!(Identity, Status, Mechanics);

// The endpoint table takes plain type names, so each reply type is named here.
pub type HomeReply = Reply<AxisAngles>;
pub type MoveReply = Reply<MoveReport>;
pub type MeasureReply = Reply<Sample>;
pub type ScanReply = Reply<ScanAccepted>;
pub type DetectionReply = Reply<DetectionReport>;
pub type SanityReply = Reply<()>;
pub type LearnReply = Reply<LearnReport>;
pub type SafetyReply = Reply<()>;
pub type PauseReply = Reply<Status>;
pub type ContinueReply = Reply<Status>;
pub type VisitReply = Reply<VisitsQueued>;

/// The one table of the head's endpoints: the command each carries, its
/// marker type, request, response, path and [`Latency`]. It makes
/// postcard-rpc's endpoints (keys, schemas, [`ENDPOINT_LIST`]), their
/// [`HeadEndpoint`] latencies and [`for_each_endpoint!`], which hands the
/// commands to code generated per endpoint (the firmware's `Command` and
/// `decode`). A new endpoint is a row here and its arm in the firmware's
/// `handle` (which the compiler asks for); the host's client sends any
/// endpoint of the table (`HeadClient::request`), and a response type that cannot
/// be refused also needs its line in `always_accepted!`. The firmware's
/// `dispatch.rs` imports its request type, as
/// the generated code names request types as the caller sees them. Each
/// type is one token (postcard-rpc's table takes no paths or generics): a
/// reply type is an alias above.
macro_rules! head_endpoints {
    (
        $d:tt
        | Command | EndpointTy | RequestTy | ResponseTy | Path | Latency |
        | $(-)* | $(-)* | $(-)* | $(-)* | $(-)* | $(-)* |
        $( | $cmd:ident | $ep:ident | $req:tt | $resp:tt | $path:literal | $lat:ident | )*
    ) => {
        endpoints! {
            list = ENDPOINT_LIST;
            | EndpointTy | RequestTy | ResponseTy | Path |
            | ---------- | --------- | ---------- | ---- |
            $( | $ep | $req | $resp | $path | )*
        }

        $( impl HeadEndpoint for $ep {
            const LATENCY: Latency = Latency::$lat;
        } )*

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
    | Command    | EndpointTy            | RequestTy         | ResponseTy              | Path                 | Latency  |
    | -------    | ----------            | ---------         | ----------              | ----                 | -------  |
    | Identify   | IdentifyEndpoint      | ()                | Identity                | "gonio/identify"     | Prompt   |
    | Status     | StatusEndpoint        | ()                | Status                  | "gonio/status"       | Prompt   |
    | Mechanics  | MechanicsEndpoint     | ()                | Mechanics               | "gonio/mechanics"    | Prompt   |
    | Home       | HomeEndpoint          | HomeRequest       | HomeReply               | "gonio/home"         | Homing   |
    | Move       | MoveEndpoint          | Geometry          | MoveReply               | "gonio/move"         | Motion   |
    | Measure    | MeasureEndpoint       | MeasureRequest    | MeasureReply            | "gonio/measure"      | Motion   |
    | Scan       | ScanEndpoint          | ScanSpec          | ScanReply               | "gonio/scan"         | Prompt   |
    | Abort      | AbortEndpoint         | ()                | Status                  | "gonio/abort"        | Prompt   |
    | Detection  | DetectionEndpoint     | DetectionSettings | DetectionReply          | "gonio/detection"    | Prompt   |
    | Sanity     | SanityEndpoint        | SanityConfig      | SanityReply             | "gonio/sanity"       | Prompt   |
    | Learn      | LearnEndpoint         | LearnRequest      | LearnReply              | "gonio/learn"        | Motion   |
    | Safety     | SafetyEndpoint        | SafetySettings    | SafetyReply             | "gonio/safety"       | Prompt   |
    | Pause      | PauseEndpoint         | ()                | PauseReply              | "gonio/pause"        | Motion   |
    | Continue   | ContinueEndpoint      | ()                | ContinueReply           | "gonio/continue"     | Prompt   |
    | Visits     | VisitEndpoint         | VisitChunk        | VisitReply              | "gonio/visits"       | Motion   |
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
