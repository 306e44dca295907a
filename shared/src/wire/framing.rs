//! COBS framing for byte-stream links (the chip's CDC-ACM port, the simulated
//! head's pseudo-terminal): each frame is COBS-encoded and ends with a zero
//! byte, exactly what postcard-rpc's `cobs-serial` host client speaks.

use postcard_rpc::accumulator::raw::{CobsAccumulator, FeedResult};

/// Largest frame (header + body) either side sends.
pub const MAX_FRAME: usize = 256;
/// Largest encoded frame: COBS adds one byte per 254, plus the terminator.
pub const MAX_ENCODED: usize = MAX_FRAME + MAX_FRAME / 254 + 2;

/// Encodes `frame` into `out`; returns the encoded length including the
/// terminating zero, or `None` if `out` is too small.
pub fn encode(frame: &[u8], out: &mut [u8]) -> Option<usize> {
    if out.len() < cobs::max_encoding_length(frame.len()) + 1 {
        return None;
    }
    let n = cobs::encode(frame, out);
    out[n] = 0;
    Some(n + 1)
}

/// Reassembles frames from a byte stream.
pub struct Decoder {
    acc: CobsAccumulator<MAX_ENCODED>,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    pub const fn new() -> Self {
        Self {
            acc: CobsAccumulator::new(),
        }
    }

    /// Feeds bytes; calls `on_frame` for every complete, well-formed frame.
    /// Over-long and corrupt frames are dropped (the host times out and
    /// retries); the decoder resynchronises on the next zero byte.
    pub fn feed(&mut self, mut bytes: &[u8], mut on_frame: impl FnMut(&[u8])) {
        while !bytes.is_empty() {
            bytes = match self.acc.feed(bytes) {
                FeedResult::Consumed => &[],
                FeedResult::OverFull(rest) | FeedResult::DeserError(rest) => rest,
                FeedResult::Success { data, remaining } => {
                    // The accumulator holds an encoded frame, which decodes
                    // to a little more than MAX_FRAME at most (found by the
                    // frame fuzzer): such a frame is refused here.
                    if data.len() <= MAX_FRAME {
                        on_frame(data);
                    }
                    remaining
                }
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_survive_split_and_garbage() {
        let mut out = [0u8; MAX_ENCODED];
        let frame = [1u8, 0, 2, 0, 0, 3];
        let n = encode(&frame, &mut out).unwrap();
        let mut stream = std::vec![0xffu8, 0x13, 0]; // garbage, then a terminator
        stream.extend_from_slice(&out[..n]);
        stream.extend_from_slice(&out[..n]);
        let mut got = std::vec::Vec::new();
        let mut d = Decoder::new();
        for chunk in stream.chunks(3) {
            d.feed(chunk, |f| got.push(f.to_vec()));
        }
        assert_eq!(got, std::vec![frame.to_vec(), frame.to_vec()]);
    }
}
