//! Chip entry point: clocks, peripherals, tasks.

mod adc_stream;
mod clocks;
mod cpu;
mod fault;
mod guard;
mod pins;
mod restart;
mod sentry;
mod step_timer;
mod usb_link;
mod watchdog;

use adc_stream::TimedAdc;
use defmt_rtt as _;
use embassy_executor::{raw, Spawner};
use embassy_futures::select::{select, Either};
use embassy_stm32::{bind_interrupts, peripherals, usb};
use embassy_time::Timer;
use gonio_firmware::head::HeadInfo;
use gonio_firmware::hw::{Board, Clock, Hardware};
use gonio_firmware::Head;
use static_cell::StaticCell;
use step_timer::StepTimer5;

bind_interrupts!(pub struct Irqs {
    OTG_FS => usb::InterruptHandler<peripherals::USB_OTG_FS>;
    TIM5 => step_timer::StepInterrupt;
    EXTI15_10 => sentry::EstopInterrupt;
    TIM7 => guard::GuardInterrupt;
});

/// The chip's types for the core.
pub struct Stm32Board;

impl Board for Stm32Board {
    type Out = embassy_stm32::gpio::Output<'static>;
    type In = embassy_stm32::gpio::Input<'static>;
    type Adc = TimedAdc;
    type Steps = StepTimer5;
    type Delay = embassy_time::Delay;
    type Clock = UptimeClock;
}

/// Microseconds since boot, from embassy-time (1 MHz tick).
pub struct UptimeClock;

impl Clock for UptimeClock {
    fn now_us(&self) -> u64 {
        embassy_time::Instant::now().as_micros()
    }
}

/// The head lives in a static, built in a function of its own: `main`'s
/// poll frame, which every request is handled on top of, then holds none
/// of its temporaries (31 KiB when built in `main`, enough for a
/// measurement's frames to overflow the 64 KiB stack; `chip-bench`'s
/// `board.stack_bytes_max` measures the image's deepest stack).
#[inline(never)]
fn make_head(hw: Hardware<Stm32Board>, info: HeadInfo) -> &'static mut Head<Stm32Board> {
    static HEAD: StaticCell<Head<Stm32Board>> = StaticCell::new();
    HEAD.init(Head::new(gonio_firmware::config::REFERENCE, hw, info))
}

/// Reset lands here: the thread-mode executor, its loop watched by the
/// guard (guard.rs), runs `run`.
#[cortex_m_rt::entry]
fn main() -> ! {
    static EXECUTOR: StaticCell<raw::Executor> = StaticCell::new();
    // The context embassy's thread-mode pender expects (a SEV wakes the loop).
    let executor: &'static raw::Executor = EXECUTOR.init(raw::Executor::new(usize::MAX as *mut ()));
    let spawner = executor.spawner();
    spawner.must_spawn(run(spawner));
    guard::run(executor)
}

#[embassy_executor::task]
async fn run(spawner: Spawner) {
    // On the HSI until the crystal has passed its check (clocks.rs).
    let crystal = clocks::check_crystal();
    let p = embassy_stm32::init(clocks::tree(crystal.is_ok()));
    if crystal.is_ok() {
        clocks::watch_crystal();
    }
    cpu::setup();
    defmt::info!("gonio head {} starting", env!("CARGO_PKG_VERSION"));
    // Read before anything else can hang: the pins come up safe (pins.rs),
    // the watchdog then guards the rest.
    let restarted_by_watchdog = watchdog::reset_cause();
    let restarted_for = restart::take_cause();
    watchdog::start(&spawner, p.IWDG);
    guard::start(p.TIM7);
    let pins = pins::Pins::new(
        p.PA1, p.PA6, p.PB0, p.PB1, p.PB2, p.PC0, p.PC1, p.PC2, p.PC3, p.PC4, p.PC5, p.PC6, p.PC7, p.PC8, p.PC9, p.PC10, p.PC11,
    );
    let adc = TimedAdc::new(p.ADC1, pins.photodiode, p.DMA2_CH0, p.TIM2, p.TIM3, pins.chop);
    let steps = StepTimer5::new(p.TIM5, pins.step);
    let hw = Hardware::<Stm32Board> {
        dir: pins.dir,
        enable_n: pins.enable_n,
        home: pins.home,
        gain: pins.gain,
        laser: pins.laser,
        adc,
        steps,
        delay: embassy_time::Delay,
        clock: UptimeClock,
    };
    let mut link = usb_link::start(&spawner, p.USB_OTG_FS, p.PA12, p.PA11);
    let mut sentry = sentry::ChipSentry::new(p.PB12);
    let info = HeadInfo {
        board: pins::NAME,
        serial: heapless::String::try_from(embassy_stm32::uid::uid_hex()).unwrap_or_default(),
        simulated: false,
        protocol_version: gonio_shared::PROTOCOL_VERSION,
    };
    let head = make_head(hw, info);
    head.prepare();
    if restarted_by_watchdog {
        head.restarted_by(gonio_shared::Fault::WatchdogReset);
    } else if let Some(cause) = restarted_for {
        head.restarted_by(cause);
    }
    if let Err(fault) = crystal {
        defmt::warn!("{}", defmt::Display2Format(&fault));
        head.inhibit_laser(fault);
    } else if cfg!(feature = "no-laser") {
        head.inhibit_laser(gonio_shared::Fault::LaserDisabled);
    }
    loop {
        // Serve until the host goes away (the head is then in its safe
        // state), then wait for the next connection.
        head.serve(&mut link, &mut sentry).await;
        // Between sessions the head is alive too: it waits, safe.
        while let Either::Second(()) = select(link.wait_connection(), Timer::after_millis(250)).await {
            sentry::alive();
        }
    }
}
