//! The clock tree, built on the crystal only once the crystal is known
//! good. embassy-stm32 turns the crystal (HSE) on and waits for HSERDY with
//! no timeout, so a dead crystal would hang the board before its watchdog
//! or its first log line; and it trusts the frequency it is told, so a
//! 12 MHz crystal on this 8 MHz board would give a 252 MHz core and a
//! 72 MHz USB clock. So first, on the internal oscillator (HSI, 16 MHz at
//! reset): HSEON, HSERDY awaited for at most [`START_TIMEOUT_MS`], then the
//! crystal counted against the HSI on TIM11 (`gonio_firmware::crystal`).
//! A crystal that fails either is left out of the tree: the PLL runs from
//! the HSI (±1 %, so the USB clock may miss its ±0.25 %), and the head
//! keeps its laser inhibited and says why (`Head::inhibit_laser`). One
//! that passes is watched by the clock security system: should it stop,
//! the NMI makes the pins safe and restarts the chip (`restart.rs`).

use embassy_stm32::pac;
use embassy_stm32::pac::timer::{regs, vals::CcmrInputCcs};
use embassy_stm32::Config;
use gonio_firmware::config::CRYSTAL_HZ;
use gonio_firmware::crystal;
use gonio_shared::Fault;

/// How long the crystal may take to start (ms): ST's HSE_STARTUP_TIMEOUT;
/// a crystal starts in about 2 ms.
const START_TIMEOUT_MS: u32 = 100;
/// TIM11 counts the HSI and wraps every 2¹⁶ ticks (4.1 ms): the start's
/// timeout in wraps.
const START_WRAPS: u32 = (START_TIMEOUT_MS * (crystal::HSI_HZ / 1000)).div_ceil(1 << 16);
/// A capture later than this many wraps: the crystal stopped counting.
const CAPTURE_WRAPS: u32 = 2;
/// Counts tried before one without an overcapture is given up on.
const COUNTS: u32 = 3;
/// TIM11_OR's TI1_RMP = 10: HSE_RTC on channel 1.
const TI1_HSE_RTC: u32 = 0b10;
/// SR with UIF written 0 and the other flags 1 (rc_w0: only UIF clears).
const CLEAR_UIF: regs::Sr1ch = regs::Sr1ch(1 << 1 | 1 << 9);

/// Starts the crystal and counts it against the HSI; on failure the
/// crystal is off again. TIM11 is left disabled, its clock gated.
pub fn check_crystal() -> Result<(), Fault> {
    let (rcc, tim) = (pac::RCC, pac::TIM11);
    rcc.apb2enr().modify(|w| w.set_tim11en(true));
    // A read back: the clock is on before the timer's first access.
    let _ = rcc.apb2enr().read();
    rcc.cfgr().modify(|w| w.set_rtcpre(crystal::RTC_PRESCALER as u8));
    tim.psc().write_value(0);
    tim.arr().write(|w| w.set_arr(0xFFFF));
    tim.egr().write(|w| w.set_ug(true));
    tim.sr().write_value(regs::Sr1ch(0));
    tim.cr1().write(|w| w.set_cen(true));
    rcc.cr().modify(|w| w.set_hseon(true));
    let measured_hz = if within(START_WRAPS, || rcc.cr().read().hserdy()) {
        counted()
    } else {
        0
    };
    tim.cr1().write(|_| {});
    tim.ccer().write(|_| {});
    tim.or().write_value(0);
    rcc.apb2enr().modify(|w| w.set_tim11en(false));
    if crystal::matches(measured_hz, CRYSTAL_HZ) {
        return Ok(());
    }
    rcc.cr().modify(|w| w.set_hseon(false));
    Err(Fault::Crystal {
        measured_khz: (measured_hz + 500) / 1000,
        expected_khz: CRYSTAL_HZ / 1000,
    })
}

/// The crystal's frequency (Hz) over [`COUNTS`] tries: a capture missed
/// (CC1OF: the core held up, by a debugger at boot) spans two intervals
/// and is counted again.
fn counted() -> u32 {
    let tim = pac::TIM11;
    let mut hz = 0;
    for _ in 0..COUNTS {
        tim.sr().write_value(regs::Sr1ch(0));
        hz = count();
        if !tim.sr().read().ccof(0) {
            break;
        }
    }
    hz
}

/// HSI ticks over [`crystal::CAPTURES`] captures of HSE_RTC, as a
/// frequency (Hz); 0 when a capture does not come.
fn count() -> u32 {
    let tim = pac::TIM11;
    tim.or().write_value(TI1_HSE_RTC);
    tim.ccmr_input(0).write(|w| {
        w.set_ccs(0, CcmrInputCcs::TI4);
        w.set_icpsc(0, 0b11);
    });
    tim.ccer().write(|w| w.set_cce(0, true));
    let capture = || within(CAPTURE_WRAPS, || tim.sr().read().ccif(0)).then(|| tim.ccr(0).read().ccr());
    // The first capture only starts the count: it may end a partial group.
    let Some(mut last) = capture() else { return 0 };
    let mut ticks = 0u32;
    for _ in 0..crystal::CAPTURES {
        let Some(at) = capture() else { return 0 };
        ticks += u32::from(at.wrapping_sub(last));
        last = at;
    }
    crystal::measured_hz(ticks)
}

/// Polls `ready` while TIM11 wraps at most `wraps` times; whether it came.
/// A poll takes several of the counter's ticks (it counts the HSI the core
/// runs on), so a poll per tick bounds the wait too: a TIM11 that does not
/// count cannot hang the boot.
fn within(wraps: u32, mut ready: impl FnMut() -> bool) -> bool {
    let tim = pac::TIM11;
    let mut seen = 0;
    for _ in 0..(wraps + 1) << 16 {
        if ready() {
            return true;
        }
        if tim.sr().read().uif() {
            tim.sr().write_value(CLEAR_UIF);
            seen += 1;
            if seen > wraps {
                return false;
            }
        }
    }
    false
}

/// A 168 MHz core and the 48 MHz USB clock, from the 8 MHz crystal (÷4
/// ×168 ÷2, ÷7) or, when it failed its check, from the 16 MHz HSI (÷8 ×168
/// ÷2, ÷7): the same VCO, the same clocks.
pub fn tree(crystal_good: bool) -> Config {
    use embassy_stm32::rcc::{mux, AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllMul, PllPDiv, PllPreDiv, PllQDiv, PllSource, Sysclk};
    use embassy_stm32::time::Hertz;
    let mut config = Config::default();
    let (source, prediv) = if crystal_good {
        config.rcc.hse = Some(Hse {
            freq: Hertz(CRYSTAL_HZ),
            mode: HseMode::Oscillator,
        });
        (PllSource::HSE, PllPreDiv::DIV4)
    } else {
        (PllSource::HSI, PllPreDiv::DIV8)
    };
    config.rcc.pll_src = source;
    config.rcc.pll = Some(Pll {
        prediv,
        mul: PllMul::MUL168,
        divp: Some(PllPDiv::DIV2),
        divq: Some(PllQDiv::DIV7),
        divr: None,
    });
    config.rcc.ahb_pre = AHBPrescaler::DIV1;
    config.rcc.apb1_pre = APBPrescaler::DIV4;
    config.rcc.apb2_pre = APBPrescaler::DIV2;
    config.rcc.sys = Sysclk::PLL1_P;
    config.rcc.mux.clk48sel = mux::Clk48sel::PLL1_Q;
    config.dma_interrupt_priority = super::cpu::DMA;
    config
}

/// The clock security system on: a crystal that stops from here on raises
/// the NMI (`restart.rs`) instead of stopping the core.
pub fn watch_crystal() {
    pac::RCC.cr().modify(|w| w.set_csson(true));
}
