//! Frames as the host sends them to the head and reads them back, for tests
//! that drive the firmware frame by frame (`gonio_sim::FrameHead`):
//! requests encoded and sealed, the head's scan events and replies decoded;
//! and the fuzz targets' bodies (`fuzz`), which send such frames.

pub mod fuzz;

use gonio_acquire::scan_order::visit_order;
use gonio_firmware::config::REFERENCE;
use gonio_firmware::dispatch;
use gonio_firmware::motion::PARK;
use gonio_shared::icd::{ScanEndpoint, ScanEventTopic, VisitEndpoint};
use gonio_shared::wire::{check, framing};
use gonio_shared::{ScanEvent, ScanSpec, VisitChunk, VISIT_CHUNK, VISIT_QUEUE};
use gonio_sim::Sent;
use postcard_rpc::header::{VarHeader, VarKey, VarKeyKind, VarSeq};
use postcard_rpc::standard_icd::{WireError, ERROR_KEY};
use postcard_rpc::{Endpoint, Key, Topic};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// A request frame (8-byte key), without its check.
pub fn request<E: Endpoint>(req: &E::Request) -> Vec<u8>
where
    E::Request: Serialize,
{
    let mut buf = vec![0u8; framing::MAX_FRAME];
    let n = dispatch::encode(E::REQ_KEY, VarKeyKind::Key8, VarSeq::Seq4(1), req, &mut buf).unwrap_or(0);
    buf.truncate(n);
    buf
}

/// A frame with its check, as the host sends it.
pub fn sealed(mut frame: Vec<u8>) -> Vec<u8> {
    let n = frame.len();
    frame.resize(n + check::LEN, 0);
    let _ = check::seal(&mut frame, n);
    frame
}

/// A sealed request.
pub fn send<E: Endpoint>(req: &E::Request) -> Vec<u8>
where
    E::Request: Serialize,
{
    sealed(request::<E>(req))
}

/// The frames that start `spec` as a script must send them: the scan
/// request, then its visit order from `spec.first_order` in chunks, as much
/// as the head's queue takes (the host's scan driver sends the rest as the
/// scan goes; a script cannot pace it, so its scans fit in one queue). The
/// chunks name run 0, the scan the head holds.
pub fn scan_frames(spec: &ScanSpec) -> Vec<Vec<u8>> {
    let first = spec.first_order as usize;
    let order: Vec<u32> = visit_order(&REFERENCE, spec, PARK).skip(first).take(VISIT_QUEUE).collect();
    let chunks = order.chunks(VISIT_CHUNK).enumerate().map(|(j, c)| {
        send::<VisitEndpoint>(&VisitChunk {
            run: 0,
            first_order: (first + j * VISIT_CHUNK) as u32,
            indices: c.iter().copied().collect(),
        })
    });
    std::iter::once(send::<ScanEndpoint>(spec)).chain(chunks).collect()
}

/// The body of a frame the head sent under `key`, decoded.
fn body<T: DeserializeOwned>(frame: &[u8], key: Key) -> Option<T> {
    let (hdr, rest) = VarHeader::take_from_slice(check::open(frame)?)?;
    (hdr.key == VarKey::Key8(key)).then(|| postcard::from_bytes(rest).ok())?
}

/// The scan events among the frames the head sent, each with what it sent.
pub fn scan_events(sent: &[Sent]) -> Vec<(ScanEvent, &Sent)> {
    sent.iter()
        .filter_map(|s| body(&s.frame, ScanEventTopic::TOPIC_KEY).map(|e| (e, s)))
        .collect()
}

/// The replies to endpoint `E` among the frames the head sent.
pub fn replies<E: Endpoint>(sent: &[Sent]) -> Vec<E::Response>
where
    E::Response: DeserializeOwned,
{
    sent.iter().filter_map(|s| body(&s.frame, E::RESP_KEY)).collect()
}

/// The wire errors among the frames the head sent (postcard-rpc's standard
/// error key: a request it could not decode, or had no room to keep).
pub fn wire_errors(sent: &[Sent]) -> Vec<WireError> {
    sent.iter().filter_map(|s| body(&s.frame, ERROR_KEY)).collect()
}

/// The fault of a refused command's reply (`Reply<T>` is `Err(Fault)`),
/// `None` for an accepted one or a frame that is no reply.
pub fn refusal(sent: &Sent) -> Option<gonio_shared::Fault> {
    let (_, body) = VarHeader::take_from_slice(check::open(&sent.frame)?)?;
    match body.split_first()? {
        (1, fault) => postcard::from_bytes(fault).ok(),
        _ => None,
    }
}
