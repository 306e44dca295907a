//! Frames ↔ commands. Decoding is a pure function of the bytes, so it is the
//! same on the chip and on the host, is property-tested, and is the target the
//! fuzzers hit. Keys are matched at the width the host chose (postcard-rpc
//! shrinks keys when unambiguous) and replies use the same width.

use gonio_shared::icd::{AbortEndpoint, HomeRequest, MeasureRequest, PauseEndpoint, StatusEndpoint};
use gonio_shared::wire::{check, key_is};
use gonio_shared::{DetectionSettings, Geometry, LearnRequest, SafetySettings, SanityConfig, ScanSpec, VisitChunk};
use postcard_rpc::header::{VarHeader, VarKey, VarKeyKind, VarSeq};
use postcard_rpc::standard_icd::WireError;
use postcard_rpc::{Endpoint, Key};
use serde::{Deserialize, Serialize};

/// A frame that is not a valid request.
#[derive(Debug, PartialEq)]
pub enum DecodeError {
    /// No header could be read: nothing to answer to, the frame is dropped.
    NoHeader,
    /// The header is fine but the key is unknown or the body does not decode:
    /// answered on the standard error path.
    Wire(VarHeader, WireError),
}

/// What a request that arrives in the middle of an operation asks for,
/// read from its key alone (a frame that fails its check or its header is
/// [`Midway::Other`] and meets the full decoder later).
#[derive(Debug, Clone, Copy)]
pub enum Midway {
    /// Stop what runs.
    Abort,
    /// Hold the running scan.
    Pause,
    /// A status poll, answered at once with this sequence number and key
    /// width: the host polls to show it is there and expects an answer
    /// within seconds, and an operation (homing) can last minutes.
    Status(VarSeq, VarKeyKind),
    Other,
}

pub fn midway(sealed: &[u8]) -> Midway {
    let Some((hdr, _)) = check::open(sealed).and_then(VarHeader::take_from_slice) else {
        return Midway::Other;
    };
    if is::<AbortEndpoint>(&hdr.key) {
        Midway::Abort
    } else if is::<PauseEndpoint>(&hdr.key) {
        Midway::Pause
    } else if is::<StatusEndpoint>(&hdr.key) {
        Midway::Status(hdr.seq_no, hdr.key.kind())
    } else {
        Midway::Other
    }
}

/// The sequence number and key width of a request, to answer it without
/// decoding it (`None`: no valid header).
pub fn request_id(sealed: &[u8]) -> Option<(VarSeq, VarKeyKind)> {
    let (hdr, _) = check::open(sealed).and_then(VarHeader::take_from_slice)?;
    Some((hdr.seq_no, hdr.key.kind()))
}

fn is<E: Endpoint>(key: &VarKey) -> bool {
    key_is(E::REQ_KEY, key)
}

fn body<'a, T: Deserialize<'a>>(hdr: VarHeader, bytes: &'a [u8]) -> Result<T, DecodeError> {
    postcard::from_bytes(bytes).map_err(|_| DecodeError::Wire(hdr, WireError::DeserFailed))
}

/// [`Command`] and [`decode`], generated from the one table of the head's
/// endpoints (`gonio_shared::icd`): each command carries its endpoint's
/// request (`()` for an empty body).
macro_rules! commands {
    ($( $variant:ident ( $ty:ty ) = $endpoint:path ),* $(,)?) => {
        /// A request from the host, decoded.
        #[derive(Debug, Clone, PartialEq)]
        pub enum Command {
            $( $variant($ty) ),*
        }

        /// Decodes one frame into its header and command.
        pub fn decode(frame: &[u8]) -> Result<(VarHeader, Command), DecodeError> {
            let (hdr, rest) = VarHeader::take_from_slice(frame).ok_or(DecodeError::NoHeader)?;
            $(
                if is::<$endpoint>(&hdr.key) {
                    return body::<$ty>(hdr, rest).map(|r| (hdr, Command::$variant(r)));
                }
            )*
            Err(DecodeError::Wire(hdr, WireError::UnknownKey))
        }
    };
}

gonio_shared::for_each_endpoint!(commands);

/// Encodes a message under `key` (shrunk to `kind`) into `buf`; returns the
/// frame length, or `None` if it does not fit.
pub fn encode<T: Serialize + ?Sized>(key: Key, kind: VarKeyKind, seq_no: VarSeq, msg: &T, buf: &mut [u8]) -> Option<usize> {
    let mut key = VarKey::Key8(key);
    key.shrink_to(kind);
    let (hdr, rest) = VarHeader { key, seq_no }.write_to_slice(buf)?;
    let hdr_len = hdr.len();
    let body = postcard::to_slice(msg, rest).ok()?;
    Some(hdr_len + body.len())
}
