//! The crystal checked against the internal oscillator before the clock
//! tree is built on it, as arithmetic the host can test. On the chip TIM11
//! counts the internal oscillator (HSI, 16 MHz at reset) and captures every
//! 8th edge of the crystal divided by RTCPRE (HSE_RTC, which TIM11_OR's
//! TI1_RMP = 10 routes to channel 1; RM0090, RCC_CFGR and TIM11_OR); a
//! dead crystal never sets
//! HSERDY, and a wrong one (a 12 MHz crystal on a board built for 8 MHz
//! gives a 252 MHz core and a 72 MHz USB clock) is seen in the count.

/// The internal oscillator the count is in (Hz): factory-trimmed to ±1 %
/// at 25 °C (DS8626 §6.3.8).
pub const HSI_HZ: u32 = 16_000_000;

/// How far the crystal may lie from the head's, as a fraction: the HSI's
/// trim and its drift over a lab's temperatures, with room to spare; the
/// nearest crystals a board is fitted with (7.37, 10, 12 MHz for 8) lie
/// further.
pub const TOLERANCE: f64 = 0.05;

/// Crystal edges per capture: the input prescaler at its largest (IC1PSC = /8).
pub const EDGES_PER_CAPTURE: u32 = 8;

/// RTCPRE, the crystal's divider into HSE_RTC: its largest, 31, so that
/// captures come as seldom as they can (every 496 HSI ticks for 8 MHz,
/// against a poll of a few dozen instructions: none is missed) while
/// HSE_RTC stays within its 1 MHz for any crystal up to 31 MHz.
pub const RTC_PRESCALER: u32 = 31;

/// Captures counted over: 4 096 crystal periods, 7 936 HSI ticks for
/// 8 MHz (the count resolved to 0.013 %); two captures lie within the
/// 16-bit counter's wrap for any crystal above 61 kHz.
pub const CAPTURES: u32 = 16;

/// The crystal's frequency (Hz) from `ticks` of the HSI over
/// [`CAPTURES`] captures; 0 for no ticks.
pub fn measured_hz(ticks: u32) -> u32 {
    if ticks == 0 {
        return 0;
    }
    let periods = (CAPTURES * EDGES_PER_CAPTURE * RTC_PRESCALER) as u64;
    ((periods * HSI_HZ as u64 + ticks as u64 / 2) / ticks as u64).min(u32::MAX as u64) as u32
}

/// Whether a crystal measured at `measured_hz` is the head's `expected_hz`.
pub fn matches(measured_hz: u32, expected_hz: u32) -> bool {
    (measured_hz as f64 - expected_hz as f64).abs() <= expected_hz as f64 * TOLERANCE
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The HSI ticks a crystal of `hz` takes over the captures.
    fn ticks(hz: f64) -> u32 {
        (f64::from(CAPTURES * EDGES_PER_CAPTURE * RTC_PRESCALER) * f64::from(HSI_HZ) / hz).round() as u32
    }

    #[test]
    fn the_heads_crystal_passes_and_its_neighbours_do_not() {
        assert_eq!(ticks(8e6), 7936);
        let cases = [
            (8e6, true),
            (8e6 * 1.03, true),
            (8e6 * 0.97, true),
            (7.3728e6, false),
            (10e6, false),
            (12e6, false),
            (25e6, false),
            (4e6, false),
        ];
        for (hz, good) in cases {
            let m = measured_hz(ticks(hz));
            assert!((m as f64 - hz).abs() < hz * 1e-3, "{hz} Hz read as {m}");
            assert_eq!(matches(m, 8_000_000), good, "{hz} Hz");
        }
        assert_eq!(measured_hz(0), 0);
        assert!(!matches(0, 8_000_000));
    }

    #[test]
    fn captures_are_sparse_and_fit_the_counter() {
        for hz in [0.26e6, 4e6, 8e6, 12e6, 25e6, 31e6] {
            assert!(hz / f64::from(RTC_PRESCALER) <= 1e6, "HSE_RTC over 1 MHz at {hz}");
            let per_capture = f64::from(EDGES_PER_CAPTURE * RTC_PRESCALER) * f64::from(HSI_HZ) / hz;
            assert!(per_capture < 65_536.0, "{hz}: a capture wraps the counter");
        }
    }
}
