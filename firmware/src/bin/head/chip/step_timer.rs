//! STEP pulses from TIM5 (32-bit, 1 MHz). Compare channel 1 fires at each
//! tick the core's [`Executor`] asks for — a step that is due or a pulse that
//! is over — and the executor raises and drops the STEP pins. When every
//! queue is empty the interrupt signals the waiting core. No step is ever
//! timed by software.

use core::cell::RefCell;
use embassy_stm32::gpio::Output;
use embassy_stm32::interrupt::typelevel::{Handler, Interrupt, TIM5 as Tim5Irq};
use embassy_stm32::peripherals::TIM5;
use embassy_stm32::timer::low_level::Timer;
use embassy_stm32::Peri;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::signal::Signal;
use gonio_firmware::config::REFERENCE;
use gonio_firmware::hw::{QueueFull, StepBlock, StepTimer};
use gonio_firmware::motion::executor::Executor;
use gonio_firmware::motion::step_irq::{self, CompareTimer};
use gonio_firmware::units;
use gonio_shared::Axis;

const TICK_HZ: u32 = 1_000_000;

/// The executor and the counter value its tick 0 corresponds to.
struct State {
    exec: Executor<Output<'static>>,
    origin: u32,
}

static STATE: Mutex<CriticalSectionRawMutex, RefCell<Option<State>>> = Mutex::new(RefCell::new(None));
static DONE: Signal<CriticalSectionRawMutex, [u32; 3]> = Signal::new();

fn regs() -> embassy_stm32::pac::timer::TimGp32 {
    embassy_stm32::pac::TIM5
}

/// TIM5's counter and compare channel 1, for the core's interrupt logic
/// ([`step_irq`]), which also closes the races of arming a compare.
struct Tim5Compare;

impl CompareTimer for Tim5Compare {
    fn count(&self) -> u32 {
        regs().cnt().read()
    }
    fn set_compare(&mut self, at: u32) {
        regs().ccr(0).write_value(at);
    }
    fn clear_match(&mut self) {
        regs().sr().modify(|w| w.set_ccif(0, false));
    }
    fn enable_interrupt(&mut self, on: bool) {
        regs().dier().modify(|w| w.set_ccie(0, on));
    }
}

pub struct StepInterrupt;

impl Handler<Tim5Irq> for StepInterrupt {
    unsafe fn on_interrupt() {
        STATE.lock(|s| {
            let mut s = s.borrow_mut();
            let Some(st) = s.as_mut() else {
                Tim5Compare.clear_match();
                return;
            };
            if let Some(emitted) = step_irq::on_compare(&mut st.exec, &mut Tim5Compare, st.origin) {
                DONE.signal(emitted);
            }
        });
    }
}

pub struct StepTimer5 {
    _timer: Timer<'static, TIM5>,
    /// A started move has not been waited for to its end yet.
    running: bool,
}

impl StepTimer5 {
    pub fn new(tim: Peri<'static, TIM5>, step_pins: [Output<'static>; 3]) -> Self {
        let timer = Timer::new(tim);
        let psc = (timer.get_clock_frequency().0 / TICK_HZ).saturating_sub(1);
        regs().psc().write_value(psc as u16);
        timer.set_max_compare_value(u32::MAX);
        timer.generate_update_event();
        let pulse = units::step_pulse_ticks(&REFERENCE.driver, TICK_HZ);
        STATE.lock(|s| {
            *s.borrow_mut() = Some(State {
                exec: Executor::new(step_pins, pulse),
                origin: 0,
            })
        });
        timer.start();
        Tim5Irq::unpend();
        // SAFETY: the handler is bound in `Irqs` and shares state only
        // through the critical-section mutex.
        unsafe { Tim5Irq::enable() };
        StepTimer5 {
            _timer: timer,
            running: false,
        }
    }

    fn with<R>(f: impl FnOnce(&mut State) -> R) -> Option<R> {
        STATE.lock(|s| s.borrow_mut().as_mut().map(f))
    }
}

impl StepTimer for StepTimer5 {
    const TICK_HZ: u32 = TICK_HZ;

    fn push(&mut self, axis: Axis, block: StepBlock) -> Result<(), QueueFull> {
        Self::with(|s| s.exec.push(axis, block)).unwrap_or(Err(QueueFull))
    }

    fn start(&mut self) {
        let done = Self::with(|s| {
            // In the critical section: an interrupt of the last move cannot
            // signal between this reset and the new move's compare.
            DONE.reset();
            // Tick 0 a little ahead, so the first step is not already late.
            s.origin = Tim5Compare.count().wrapping_add(10);
            let first = s.exec.start();
            step_irq::schedule(&mut s.exec, &mut Tim5Compare, s.origin, first)
        });
        // An empty move is over at once: `finished` reads its counts.
        self.running = matches!(done, Some(None));
    }

    async fn finished(&mut self) -> [u32; 3] {
        if !self.running {
            return Self::with(|s| s.exec.emitted()).unwrap_or([0; 3]);
        }
        let emitted = DONE.wait().await;
        self.running = false;
        emitted
    }

    fn emitted(&self) -> [u32; 3] {
        Self::with(|s| s.exec.emitted()).unwrap_or([0; 3])
    }

    fn brake(&mut self, brake_ticks: [f32; 3]) {
        // In the critical section the interrupt cannot fire between the
        // executor's new schedule and the compare written for it.
        Self::with(|s| {
            let next = s.exec.brake(brake_ticks);
            if let Some(emitted) = step_irq::schedule(&mut s.exec, &mut Tim5Compare, s.origin, next) {
                DONE.signal(emitted);
            }
        });
    }

    fn clear(&mut self) {
        Self::with(|s| {
            Tim5Compare.enable_interrupt(false);
            Tim5Compare.clear_match();
            s.exec.clear();
        });
    }
}
