//! The head's side of its conversation with the host, kept apart from the
//! instrument (`Head`'s laser, stages, detector and scan): the key width the
//! host chose, the sequence number of the topics, and a scan event that must
//! follow the reply being sent.

use gonio_shared::ScanEvent;
use postcard_rpc::header::VarKeyKind;

#[derive(Debug)]
pub(crate) struct Conversation {
    /// Key width the host uses; replies and topics follow it.
    pub(crate) key_kind: VarKeyKind,
    /// Sequence number of the next topic message.
    pub(crate) topic_seq: u32,
    /// A scan event to publish after the current reply (an abort's `Stopped`).
    pub(crate) pending_event: Option<ScanEvent>,
}

impl Default for Conversation {
    fn default() -> Self {
        Conversation {
            key_kind: VarKeyKind::Key8,
            topic_seq: 0,
            pending_event: None,
        }
    }
}
