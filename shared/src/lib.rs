//! The message crate: every type that crosses the link between the measurement
//! head and the host, in SI units (degrees, seconds, hertz, volts).
//!
//! Like the ICD crate of postcard-rpc's examples, this crate is the single
//! definition of the protocol. Endpoints and topics (in [`icd`]) carry keys
//! hashed from their path *and* their schema, so a head and a host built from
//! different message definitions cannot silently misread each other: the head
//! answers an unknown key with a wire error, and [`Identity::protocol_version`]
//! names the mismatch.
#![cfg_attr(not(test), no_std)]

pub mod detection;
pub mod fault;
pub mod geometry;
pub mod icd;
pub mod identity;
pub mod lobe_pattern;
pub mod mechanics;
pub mod models;
pub mod row_turn;
pub mod safety;
pub mod sample;
pub mod sanity;
pub mod scan;
pub mod status;
pub mod sweep;
pub mod wire;

pub use detection::{DetectionReport, DetectionSettings, LearnReport, LearnRequest, Reference};
pub use fault::{Axis, Fault, Field, Unreachable};
pub use geometry::{AxisAngles, Geometry};
pub use identity::{Capabilities, Identity, PROTOCOL_VERSION};
pub use lobe_pattern::{LobePatterns, Rings};
pub use mechanics::{AxisMechanics, Mechanics};
pub use models::{ModelSpec, MODELS};
pub use safety::SafetySettings;
pub use sample::{Sample, SampleFlags, Signal};
pub use sanity::{SanityConfig, SanityKind, SanityModel};
pub use scan::{
    AngleRange, Asked, ScanAccepted, ScanEvent, ScanSpec, SweepRow, SweepScan, Visit, VisitChunk, VisitsQueued, VISIT_CHUNK, VISIT_QUEUE,
};
pub use status::{HeadState, Status};
pub use sweep::{SweepLobe, SweepReport, SweepRequest, SweptSample};

/// Every fallible command answers with this: the result or the reason it was
/// refused. A refused command has no side effect (nothing moved, laser unchanged).
pub type Reply<T> = Result<T, Fault>;
