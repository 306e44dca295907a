//! The frame check sequence: every frame on every link carries a CRC-32 of
//! its bytes at its end, so that a frame damaged on the way is dropped
//! instead of decoded into wrong values (postcard decodes most corrupted
//! bodies without complaint: a flipped bit in a sample's voltage is still a
//! float). A dropped frame is a lost frame: the host's timeouts and the scan's
//! continuity check recover it. Both the head (`serve`) and the host's wires
//! use these two functions.

use crc::{Crc, CRC_32_ISO_HDLC};

/// Bytes the check adds to a frame.
pub const LEN: usize = 4;

const CRC32: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// Appends the check to the `len` frame bytes at the start of `buf`; returns
/// the sealed length, or `None` if it does not fit.
pub fn seal(buf: &mut [u8], len: usize) -> Option<usize> {
    let end = len.checked_add(LEN)?;
    let sum = CRC32.checksum(buf.get(..len)?);
    buf.get_mut(len..end)?.copy_from_slice(&sum.to_le_bytes());
    Some(end)
}

/// The frame without its check, if the check holds.
pub fn open(sealed: &[u8]) -> Option<&[u8]> {
    let split = sealed.len().checked_sub(LEN)?;
    let (frame, sum) = sealed.split_at(split);
    (CRC32.checksum(frame).to_le_bytes() == sum).then_some(frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_single_bit_flip_and_truncation_is_caught() {
        let mut buf = [0u8; 64];
        for (i, b) in buf.iter_mut().enumerate().take(40) {
            *b = (i * 37) as u8;
        }
        let n = seal(&mut buf, 40).unwrap();
        assert_eq!(open(&buf[..n]), Some(&buf[..40]));
        for bit in 0..n * 8 {
            let mut bad = buf;
            bad[bit / 8] ^= 1 << (bit % 8);
            assert_eq!(open(&bad[..n]), None, "bit {bit}");
        }
        for cut in 0..n {
            assert_eq!(open(&buf[..cut]), None, "cut at {cut}");
        }
        assert_eq!(seal(&mut buf, 61), None);
    }
}
