//! The link to the host, as the core sees it: whole frames in, whole frames
//! out. The chip carries them over USB (COBS on a CDC-ACM byte stream), the
//! simulated head over a pseudo-terminal or in-process channels.

/// Why a link stopped working.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkError {
    /// The host went away (cable, port closed); the head goes to its safe state.
    Closed,
}

pub trait Link {
    /// Waits for the next frame; returns its length in `buf`.
    async fn recv(&mut self, buf: &mut [u8]) -> Result<usize, LinkError>;
    /// A frame, if one is already waiting (polled between the points of a scan).
    fn try_recv(&mut self, buf: &mut [u8]) -> Option<Result<usize, LinkError>>;
    /// Sends one frame.
    async fn send(&mut self, frame: &[u8]) -> Result<(), LinkError>;
}
