//! Chop and sampling on one clock. TIM2 overflows once per ADC sample and its
//! update event (TRGO) both triggers ADC1 and clocks TIM3, whose period is M
//! TIM2 events and whose channel 1 is the 50 % chop output. Every chop period
//! therefore holds exactly M samples, and sample 0 of each block falls on the
//! chop's rising edge. DMA2 stream 0 moves the codes into a circular buffer
//! of two periods, programmed afresh for each measurement; the ring buffer
//! reports an overrun when the core falls behind, and the core flags the
//! sample.
//!
//! Two periods, not two of the longest (2 × 512 codes): the DMA wakes the
//! reader at half and full of the ring only, so a period is handed over as
//! soon as its last code lands (a swept sample's step count and time are
//! read then, not up to 511 codes later), and a chain that stops is found
//! within three periods. Programming the stream afresh (a new ring: its
//! address and count written, RM0090 §10.3.14) is also what restarts a
//! stream that stopped, and it starts each measurement at the ring's base
//! with nothing of the last one in it.
//!
//! The thread's slack is therefore one period: the settings cap the chop
//! at 1 kHz (`DetectionSettings::CHOP_HZ_MAX`), where `board-faults`
//! measures 416 µs of it at 200 kS/s; at 5 kHz every measurement overran.

use super::guard;
use embassy_futures::select::{select3, Either3};
use embassy_stm32::adc::{Adc, RxDma, SampleTime};
use embassy_stm32::dma::{ReadableRingBuffer, Request, TransferOptions};
use embassy_stm32::gpio::{Flex, OutputType, Pull, Speed};
use embassy_stm32::pac;
use embassy_stm32::peripherals::{ADC1, DMA2_CH0, PA1, PA6, TIM2, TIM3};
use embassy_stm32::timer::low_level::{MasterMode, OutputCompareMode, SlaveMode, Timer, TriggerSource};
use embassy_stm32::timer::simple_pwm::{PwmPin, PwmPinConfig};
use embassy_stm32::timer::{Ch1, Channel};
use embassy_stm32::Peri;

use gonio_firmware::demod::MAX_M;
use gonio_firmware::hw::{AdcStream, ChopTiming, Overrun};
use gonio_firmware::units;
use static_cell::StaticCell;

/// ADC1 external trigger selection for TIM2 TRGO (RM0090, ADC_CR2.EXTSEL).
const EXTSEL_TIM2_TRGO: u8 = 0b0110;
/// Core cycles (168 MHz) that outlast one conversion: 84 sampling and 12
/// conversion cycles of the 21 MHz ADC clock, 4.6 µs, with margin.
const CONVERSION_CYCLES: u32 = 1_000;
/// Photodiode input: ADC123_IN1 on PA1.
const CHANNEL: usize = 1;

static DMA_BUF: StaticCell<[u16; 2 * MAX_M]> = StaticCell::new();

pub struct TimedAdc {
    /// The stream, lent to each measurement's ring.
    dma: Peri<'static, DMA2_CH0>,
    request: Request,
    /// `DMA_BUF`, lent to each measurement's ring.
    buf: *mut u16,
    ring: Option<ReadableRingBuffer<'static, u16>>,
    sample_clock: Timer<'static, TIM2>,
    chop: Timer<'static, TIM3>,
    running: bool,
    /// TIM2's input clock (Hz), as the clock tree set it up.
    timer_hz: u32,
    /// How long a period may take before the chain counts as stopped (µs).
    stall_us: u64,
    // Kept so the ADC clock and the pins stay configured.
    _adc: Adc<'static, ADC1>,
    _input: Flex<'static>,
    _chop_pin: PwmPin<'static, TIM3, Ch1>,
}

impl TimedAdc {
    pub fn new(
        adc1: Peri<'static, ADC1>,
        input: Peri<'static, PA1>,
        dma: Peri<'static, DMA2_CH0>,
        tim2: Peri<'static, TIM2>,
        tim3: Peri<'static, TIM3>,
        chop_pin: Peri<'static, PA6>,
    ) -> Self {
        let adc = Adc::new(adc1);
        let mut input = Flex::new(input);
        input.set_as_analog();
        let r = pac::ADC1;
        r.sqr1().modify(|w| w.set_l(0));
        r.sqr3().modify(|w| w.set_sq(0, CHANNEL as u8));
        r.smpr2().modify(|w| w.set_smp(CHANNEL, SampleTime::CYCLES84));
        r.cr1().modify(|w| w.set_scan(false));
        r.cr2().modify(|w| {
            w.set_cont(false);
            w.set_dma(true);
            w.set_dds(pac::adc::vals::Dds::CONTINUOUS);
            w.set_extsel(EXTSEL_TIM2_TRGO);
            w.set_exten(pac::adc::vals::Exten::DISABLED);
            w.set_adon(true);
        });
        let request = <DMA2_CH0 as RxDma<ADC1>>::request(&dma);
        let buf = DMA_BUF.init([0; 2 * MAX_M]).as_mut_ptr();

        let sample_clock = Timer::new(tim2);
        sample_clock.set_master_mode(MasterMode::UPDATE);
        let chop = Timer::new(tim3);
        chop.set_trigger_source(TriggerSource::ITR1); // TIM2 TRGO
        chop.set_slave_mode(SlaveMode::EXT_CLOCK_MODE);
        // Dark until the first measurement.
        chop.set_output_compare_mode(Channel::Ch1, OutputCompareMode::ForceInactive);
        chop.enable_channel(Channel::Ch1, true);
        // The slowest slew rate, as every output of the board (pins.rs).
        let chop_pin = PwmPin::new_with_config(
            chop_pin,
            PwmPinConfig {
                output_type: OutputType::PushPull,
                speed: Speed::Low,
                pull: Pull::None,
            },
        );
        TimedAdc {
            dma,
            request,
            buf,
            ring: None,
            timer_hz: sample_clock.get_clock_frequency().0,
            sample_clock,
            chop,
            running: false,
            stall_us: 0,
            _adc: adc,
            _input: input,
            _chop_pin: chop_pin,
        }
    }
}

impl TimedAdc {
    /// A ring of two periods of `m` codes, the stream programmed for it and
    /// running; the previous ring dropped first (its stream disabled).
    fn arm(&mut self, m: usize) -> &mut ReadableRingBuffer<'static, u16> {
        self.ring = None;
        let len = (2 * m).min(2 * MAX_M);
        // SAFETY: the buffer's only other user, the previous ring, is gone
        // (dropped above, its stream disabled); `len` is within DMA_BUF.
        let buf = unsafe { core::slice::from_raw_parts_mut(self.buf, len) };
        // SAFETY: one ring at a time holds the stream (the last is dropped).
        let dma = unsafe { self.dma.clone_unchecked() };
        // SAFETY: the DMA reads ADC1's data register, a valid 16-bit
        // peripheral address, into a buffer that lives for the program.
        let ring = unsafe {
            ReadableRingBuffer::new(
                dma,
                self.request,
                pac::ADC1.dr().as_ptr() as *mut u16,
                buf,
                TransferOptions::default(),
            )
        };
        self.ring.insert(ring)
    }
}

impl AdcStream for TimedAdc {
    fn timer_hz(&self) -> u32 {
        self.timer_hz
    }

    const BITS: u8 = 12;

    fn start(&mut self, t: ChopTiming) {
        self.stop();
        let m = t.samples_per_period.max(2) as u32;
        // The ring's two periods plus one, and a millisecond for the DMA's
        // interrupt and the executor.
        let sample_ticks = t.ticks_per_sample.max(2) as u64;
        self.stall_us = units::ticks_to_us(3 * m as u64 * sample_ticks, self.timer_hz) + 1_000;
        self.sample_clock.regs_core().psc().write_value(0);
        self.sample_clock.set_max_compare_value(t.ticks_per_sample.max(2) - 1);
        self.sample_clock.regs_core().cnt().write(|w| w.set_cnt(0));
        self.chop.set_max_compare_value((m - 1) as u16);
        self.chop.set_compare_value(Channel::Ch1, (m / 2) as u16);
        // The chop rises as TIM3 starts, one sample period before the
        // trigger of the block's first sample, and falls at the trigger of
        // sample M/2 − 1: each edge leads its block's sample by the sample
        // and hold's delay and the amplifier's lag, so that samples 0 to
        // M/2 − 1 see the light. Shown on the virtual board: with the edges
        // on the triggers of samples 0 and M/2 the amplitude reads 6 % low
        // and the phase 4° late.
        self.chop.regs_core().cnt().write(|w| w.set_cnt(0));
        self.chop.set_output_compare_mode(Channel::Ch1, OutputCompareMode::PwmMode1);
        self.chop.enable_channel(Channel::Ch1, true);
        self.chop.start();
        // A code left in the data register, or an overrun, would be the first
        // thing the DMA moves when it resumes, and would open this
        // measurement with a code of the last one, one sample out of phase
        // with the chop: read it out, clear the flags, re-arm the ADC's DMA
        // requests (an overrun stops them), then program the stream afresh.
        let adc = pac::ADC1;
        let _ = adc.dr().read();
        adc.sr().modify(|w| {
            w.set_ovr(false);
            w.set_eoc(false);
            w.set_strt(false);
        });
        adc.cr2().modify(|w| w.set_dma(false));
        adc.cr2().modify(|w| w.set_dma(true));
        self.arm(m as usize).start();
        pac::ADC1.cr2().modify(|w| w.set_exten(pac::adc::vals::Exten::RISING_EDGE));
        self.sample_clock.start();
        self.running = true;
        let sample_us = units::ticks_to_us(sample_ticks, self.timer_hz);
        guard::watch_chain(sample_us.min(u32::MAX as u64) as u32);
    }

    fn stop(&mut self) {
        guard::unwatch_chain();
        self.sample_clock.stop();
        pac::ADC1.cr2().modify(|w| w.set_exten(pac::adc::vals::Exten::DISABLED));
        // A conversion already triggered ends 96 ADC clocks (4.6 µs) later;
        // its transfer lands while the stream still runs rather than waiting
        // in the data register for the next measurement.
        cortex_m::asm::delay(CONVERSION_CYCLES);
        // Chop output driven low (forced inactive, the channel left enabled):
        // a disabled channel would leave the pin floating, and the laser's
        // modulation input must see dark between measurements.
        self.chop.set_output_compare_mode(Channel::Ch1, OutputCompareMode::ForceInactive);
        self.chop.enable_channel(Channel::Ch1, true);
        self.chop.stop();
        self.running = false;
    }

    /// A chain that stops (a trigger, conversion or transfer that no
    /// longer comes) is found by the guard within a few hundred µs, which
    /// cuts the laser and ends the read; failing that (a DMA that moves but
    /// no longer interrupts), by a period that has not arrived when the
    /// ring could have filled once more. Either way the stream stops, chop
    /// dark, and this and every later read until the next `start` fail at
    /// once, so the core ends the measurement and turns the laser off (it
    /// reports it as a lost block, `Fault::AdcOverrun` on the second),
    /// instead of waiting for ever with the laser on.
    async fn next_period(&mut self, out: &mut [u16]) -> Result<(), Overrun> {
        let (true, Some(ring), false) = (self.running, self.ring.as_mut(), guard::tripped()) else {
            if self.running {
                self.stop();
            }
            return Err(Overrun);
        };
        match select3(
            ring.read_exact(out),
            embassy_time::Timer::after_micros(self.stall_us),
            guard::trip(),
        )
        .await
        {
            Either3::First(r) => r.map(|_| ()).map_err(|_| Overrun),
            Either3::Second(()) | Either3::Third(()) => {
                self.stop();
                Err(Overrun)
            }
        }
    }
}
