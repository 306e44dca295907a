//! Why the chip restarted itself, carried across the reset: the clock
//! security system's NMI and the handler of interrupts with none of their
//! own make the pins safe and reset at once, with no time to tell the host;
//! they leave the cause in two words of RAM the startup code does not
//! clear (`.uninit`), and the head that comes up reports it in its status.
//! A word and its complement, so that the random RAM of a power-up is never
//! read as a cause.

use gonio_shared::Fault;

/// The cause's tag (upper 12 bits) and kinds (next 4 bits); the low 16 bits
/// carry the kind's value.
const TAG: u32 = 0x5AF0_0000;
const TAG_MASK: u32 = 0xFFF0_0000;
const CLOCK_STOPPED: u32 = 1;
const STRAY_INTERRUPT: u32 = 2;

/// The two words that record `fault`; `None` for a fault that does not
/// restart the chip.
pub fn encode(fault: Fault) -> Option<[u32; 2]> {
    let word = match fault {
        Fault::ClockStopped => TAG | CLOCK_STOPPED << 16,
        Fault::StrayInterrupt(n) => TAG | STRAY_INTERRUPT << 16 | n as u16 as u32,
        _ => return None,
    };
    Some([word, !word])
}

/// The fault two words record, if they record one.
pub fn decode([word, check]: [u32; 2]) -> Option<Fault> {
    if check != !word || word & TAG_MASK != TAG {
        return None;
    }
    match word >> 16 & 0xF {
        CLOCK_STOPPED => Some(Fault::ClockStopped),
        STRAY_INTERRUPT => Some(Fault::StrayInterrupt(word as u16 as i16)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cause_survives_its_words_and_noise_is_no_cause() {
        for f in [
            Fault::ClockStopped,
            Fault::StrayInterrupt(0),
            Fault::StrayInterrupt(81),
            Fault::StrayInterrupt(-11),
        ] {
            assert_eq!(decode(encode(f).unwrap()), Some(f));
        }
        assert_eq!(encode(Fault::Busy), None);
        assert_eq!(decode([0, 0]), None);
        assert_eq!(decode([0, u32::MAX]), None, "complementary, but no tag");
        let [w, c] = encode(Fault::ClockStopped).unwrap();
        assert_eq!(decode([w, c ^ 1]), None, "one bit of the check flipped");
        // Power-up RAM: a pseudo-random pair is almost never a cause.
        let mut x = 0x1234_5678u32;
        let mut found = 0;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let a = x;
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            found += usize::from(decode([a, x]).is_some());
        }
        assert_eq!(found, 0);
    }
}
