//! Pin assignment of the reference board (STM32F405RG, LQFP64).
//!
//! | function              | pin  | notes                                        |
//! |-----------------------|------|----------------------------------------------|
//! | photodiode (ADC1 IN1) | PA1  | transimpedance amplifier output              |
//! | chop (TIM3 CH1, AF2)  | PA6  | laser modulation input, 50 % duty            |
//! | laser enable          | PB0  | high = laser may emit                        |
//! | gain select bit 0/1   | PB1, PB2 | four decades of transimpedance           |
//! | rotation STEP/DIR/EN/HOME | PC0–PC3 | EN active low, HOME high = pressed   |
//! | cradle STEP/DIR/EN/HOME   | PC4–PC7 |                                      |
//! | arm STEP/DIR/EN/HOME      | PC8–PC11 |                                     |
//! | USB FS D−/D+          | PA11, PA12 |                                        |
//! | E-STOP (EXTI12)       | PB12 | NC switch to ground, pull-up: high = stop  |
//! | USB VBUS sense        | PA9  | OTG_FS_VBUS, from VBUS through a divider   |
//!
//! Home switches are normally closed to ground with the internal pull-up, so a
//! pressed switch and a broken wire both read high: homing then stops at once
//! instead of driving into the end stop. The E-STOP is wired the same way.
//! The internal pull-ups (30–50 kΩ; about 10 kΩ on PB12, which is also
//! OTG_HS_ID) alone are too weak for a metre of stage cable beside the
//! motor leads: each of these four inputs also gets a 4.7 kΩ pull-up at the
//! MCU and a capacitor to ground, 100 nF on the home inputs (τ = 0.47 ms)
//! and 10 nF on the E-STOP (τ = 47 µs, so its trip waits at most about
//! 60 µs for the input to cross its threshold). The firmware does not
//! debounce the home switches: homing reads them only with the axis
//! standing, five time constants after each chunk's last step
//! (`homing::SWITCH_SETTLE_S`), and finds the edge one microstep at a time,
//! so a bounce costs at most a microstep of the edge. Nor does it debounce
//! the E-STOP's opening, on purpose: its first edge stops the head; only
//! the release is debounced (`serve::ESTOP_DEBOUNCE_US`, sentry.rs).
//!
//! PA9 senses VBUS for the USB core (usb_link.rs) through 4.7 kΩ from VBUS
//! and 10 kΩ to ground (3.4 V): straight from the connector, a host's 5 V
//! would exceed the pin's absolute maximum (VDD + 4 V) while the head is
//! off (ST's AN4879 §2.6). The pin stays a floating input.
//!
//! PB2 is also BOOT1, sampled at reset when BOOT0 is high: a 10 kΩ
//! pull-down selects the system memory's boot loader then (RM0090 §2.4),
//! and keeps gain bit 1 low until `Pins::new` drives it.
//!
//! Every output is set to the slowest slew rate (OSPEEDR 00: up to 2 MHz,
//! edges of at most 125 ns into 50 pF by the STM32F405's datasheet): the
//! fastest signal here is a 4 µs STEP pulse, and slower
//! edges ring less on the drivers' cables and radiate less near the
//! photodiode's amplifier. Only the USB pins, set by the USB driver, are
//! fast.
//!
//! From reset until `Pins::new` runs (the boot ROM, `embassy_stm32::init`,
//! the clock start-up) every pin is a floating input. The board must hold the
//! safe state by itself meanwhile: 10 kΩ pull-downs on the laser enable (PB0)
//! and on the three STEP lines, 10 kΩ pull-ups on the three active-low EN
//! lines; the chop output (PA6) also gets a pull-down, since the laser's
//! modulation input must not see a floating level.

use embassy_stm32::gpio::{Input, Level, Output, Pull, Speed};
use embassy_stm32::peripherals::*;
use embassy_stm32::Peri;

pub const NAME: &str = "gonio head STM32F405RG rev A";

/// Darkens the laser from an interrupt, whatever the thread was doing: the
/// enable (PB0) low with one BSRR store, and the chop (PA6) held low by
/// TIM3's channel forced inactive, its pin left to the timer so that the
/// next measurement's `start` chops again. CCMR1 is read, modified and
/// written here; its only other writers are the thread's chop start and
/// stop (adc_stream.rs), and a start that this interrupts between its read
/// and its write puts the chop back on, with the enable already low, until
/// the thread's stop that follows every trip.
pub fn cut_laser() {
    use embassy_stm32::pac::{timer::vals::Ocm, GPIOB, TIM3};
    GPIOB.bsrr().write(|w| w.set_br(0, true));
    TIM3.ccmr_output(0).modify(|w| w.set_ocm(0, Ocm::FORCE_INACTIVE));
}

/// Disables the drivers (their active-low EN high) with one BSRR store,
/// whoever owns the pins: the E-STOP's backstop (guard.rs).
pub fn disable_drivers() {
    embassy_stm32::pac::GPIOC.bsrr().write(|w| {
        for axis in 0..3 {
            w.set_bs(4 * axis + 2, true);
        }
    });
}

/// Puts the pins of the table above into the safe state (laser enable and
/// chop low, STEP low, drivers disabled) by writing the GPIO registers
/// directly.
/// For the fault handler only: it runs when the owners of the pins can no
/// longer be trusted, and a BSRR write is atomic whatever they were doing.
pub fn force_safe_state() {
    use embassy_stm32::pac::gpio::vals::Moder;
    use embassy_stm32::pac::{GPIOA, GPIOB, GPIOC};
    GPIOB.bsrr().write(|w| w.set_br(0, true));
    // The chop (TIM3's output) taken from the timer: PA6 a plain output, low.
    GPIOA.bsrr().write(|w| w.set_br(6, true));
    GPIOA.moder().modify(|w| w.set_moder(6, Moder::OUTPUT));
    GPIOC.bsrr().write(|w| {
        for axis in 0..3 {
            w.set_br(4 * axis, true);
            w.set_bs(4 * axis + 2, true);
        }
    });
}

pub struct Pins {
    pub photodiode: Peri<'static, PA1>,
    pub chop: Peri<'static, PA6>,
    pub laser: Output<'static>,
    pub gain: [Output<'static>; 2],
    pub step: [Output<'static>; 3],
    pub dir: [Output<'static>; 3],
    pub enable_n: [Output<'static>; 3],
    pub home: [Input<'static>; 3],
}

fn out(pin: Peri<'static, impl embassy_stm32::gpio::Pin>, level: Level) -> Output<'static> {
    Output::new(pin, level, Speed::Low)
}

impl Pins {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        pa1: Peri<'static, PA1>,
        pa6: Peri<'static, PA6>,
        pb0: Peri<'static, PB0>,
        pb1: Peri<'static, PB1>,
        pb2: Peri<'static, PB2>,
        pc0: Peri<'static, PC0>,
        pc1: Peri<'static, PC1>,
        pc2: Peri<'static, PC2>,
        pc3: Peri<'static, PC3>,
        pc4: Peri<'static, PC4>,
        pc5: Peri<'static, PC5>,
        pc6: Peri<'static, PC6>,
        pc7: Peri<'static, PC7>,
        pc8: Peri<'static, PC8>,
        pc9: Peri<'static, PC9>,
        pc10: Peri<'static, PC10>,
        pc11: Peri<'static, PC11>,
    ) -> Self {
        Pins {
            photodiode: pa1,
            chop: pa6,
            // Power-up state is the safe state: laser off, drivers disabled.
            laser: out(pb0, Level::Low),
            gain: [out(pb1, Level::Low), out(pb2, Level::Low)],
            step: [out(pc0, Level::Low), out(pc4, Level::Low), out(pc8, Level::Low)],
            dir: [out(pc1, Level::Low), out(pc5, Level::Low), out(pc9, Level::Low)],
            enable_n: [out(pc2, Level::High), out(pc6, Level::High), out(pc10, Level::High)],
            home: [Input::new(pc3, Pull::Up), Input::new(pc7, Pull::Up), Input::new(pc11, Pull::Up)],
        }
    }
}
