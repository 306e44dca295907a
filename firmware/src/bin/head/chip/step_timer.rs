//! STEP pulses from TIM5 (32-bit, 1 MHz). Compare channel 1 fires at the next
//! scheduled step of any axis: the handler raises the STEP pins that are due,
//! advances each axis through its `(interval, count, add)` blocks, and arms
//! compare channel 2 to drop the pins after the pulse width. When every queue
//! is empty it signals the waiting core. No step is ever timed by software.

use core::cell::RefCell;
use embassy_stm32::gpio::Output;
use embassy_stm32::interrupt::typelevel::{Handler, Interrupt, TIM5 as Tim5Irq};
use embassy_stm32::peripherals::TIM5;
use embassy_stm32::timer::low_level::Timer;
use embassy_stm32::Peri;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::signal::Signal;
use gonio_firmware::board::REFERENCE;
use gonio_firmware::hw::{QueueFull, StepBlock, StepTimer};
use gonio_firmware::units;
use gonio_shared::Axis;
use heapless::Deque;

const TICK_HZ: u32 = 1_000_000;
const QUEUE: usize = 8;

/// One axis being stepped.
struct AxisRun {
    queue: Deque<StepBlock, QUEUE>,
    /// Interval (ticks) of the step just scheduled, steps left in the block.
    interval: i64,
    add: i32,
    left: u32,
    next: u32,
    emitted: u32,
    active: bool,
}

impl AxisRun {
    const fn new() -> Self {
        AxisRun {
            queue: Deque::new(),
            interval: 0,
            add: 0,
            left: 0,
            next: 0,
            emitted: 0,
            active: false,
        }
    }

    /// Loads the next block; false when the queue is empty.
    fn load(&mut self, from: u32) -> bool {
        match self.queue.pop_front() {
            Some(b) if b.count > 0 => {
                self.interval = b.interval as i64;
                self.add = b.add;
                self.left = b.count;
                self.next = from.wrapping_add(b.interval);
                true
            }
            Some(_) => self.load(from),
            None => false,
        }
    }

    /// After a step: schedule the next one, or finish.
    fn advance(&mut self) {
        self.left -= 1;
        if self.left > 0 {
            self.interval = (self.interval + self.add as i64).max(1);
            self.next = self.next.wrapping_add(self.interval as u32);
        } else {
            self.active = self.load(self.next);
        }
    }
}

struct State {
    axes: [AxisRun; 3],
    pins: Option<[Output<'static>; 3]>,
    pulse_ticks: u32,
}

static STATE: Mutex<CriticalSectionRawMutex, RefCell<State>> = Mutex::new(RefCell::new(State {
    axes: [AxisRun::new(), AxisRun::new(), AxisRun::new()],
    pins: None,
    pulse_ticks: 3,
}));
static DONE: Signal<CriticalSectionRawMutex, [u32; 3]> = Signal::new();

fn regs() -> embassy_stm32::pac::timer::TimGp32 {
    embassy_stm32::pac::TIM5
}

/// TIM5 interrupt: step edges on CC1, pulse ends on CC2.
pub struct StepInterrupt;

impl Handler<Tim5Irq> for StepInterrupt {
    unsafe fn on_interrupt() {
        let r = regs();
        let sr = r.sr().read();
        r.sr().write_value(embassy_stm32::pac::timer::regs::SrGp16(!sr.0 & !0b110));
        STATE.lock(|s| {
            let s = &mut *s.borrow_mut();
            let Some(pins) = s.pins.as_mut() else { return };
            if sr.ccif(1) {
                for p in pins.iter_mut() {
                    p.set_low();
                }
                r.dier().modify(|w| w.set_ccie(1, false));
            }
            if sr.ccif(0) {
                let now = r.cnt().read();
                let mut soonest: Option<u32> = None;
                for (ax, pin) in s.axes.iter_mut().zip(pins.iter_mut()) {
                    if !ax.active {
                        continue;
                    }
                    if (now.wrapping_sub(ax.next) as i32) >= 0 {
                        pin.set_high();
                        ax.emitted += 1;
                        ax.advance();
                    }
                    if ax.active {
                        let d = ax.next.wrapping_sub(now);
                        soonest = Some(soonest.map_or(d, |s: u32| s.min(d)));
                    }
                }
                r.ccr(1).write_value(now.wrapping_add(s.pulse_ticks));
                r.dier().modify(|w| w.set_ccie(1, true));
                match soonest {
                    Some(d) => r.ccr(0).write_value(now.wrapping_add(d.max(1))),
                    None => {
                        r.dier().modify(|w| w.set_ccie(0, false));
                        DONE.signal([0, 1, 2].map(|i| s.axes[i].emitted));
                    }
                }
            }
        });
    }
}

pub struct StepTimer5 {
    timer: Timer<'static, TIM5>,
}

impl StepTimer5 {
    pub fn new(tim: Peri<'static, TIM5>, step_pins: [Output<'static>; 3]) -> Self {
        let timer = Timer::new(tim);
        let psc = (timer.get_clock_frequency().0 / TICK_HZ).saturating_sub(1);
        regs().psc().write_value(psc as u16);
        timer.set_max_compare_value(u32::MAX);
        timer.generate_update_event();
        let pulse = units::seconds_to_ticks(REFERENCE.driver.step_pulse_s, TICK_HZ).max(1);
        STATE.lock(|s| {
            let mut s = s.borrow_mut();
            s.pins = Some(step_pins);
            s.pulse_ticks = pulse;
        });
        timer.start();
        Tim5Irq::unpend();
        // SAFETY: the handler is bound in `Irqs` and shares state only
        // through the critical-section mutex.
        unsafe { Tim5Irq::enable() };
        StepTimer5 { timer }
    }
}

impl StepTimer for StepTimer5 {
    const TICK_HZ: u32 = TICK_HZ;

    fn push(&mut self, axis: Axis, block: StepBlock) -> Result<(), QueueFull> {
        STATE.lock(|s| s.borrow_mut().axes[axis.index()].queue.push_back(block).map_err(|_| QueueFull))
    }

    async fn run(&mut self) -> [u32; 3] {
        DONE.reset();
        let now = self.timer.regs_gp32().cnt().read();
        let any = STATE.lock(|s| {
            let s = &mut *s.borrow_mut();
            let mut any = false;
            for ax in s.axes.iter_mut() {
                ax.emitted = 0;
                // All axes start from the same instant, a little ahead.
                ax.active = ax.load(now.wrapping_add(10));
                any |= ax.active;
            }
            any
        });
        if !any {
            return [0; 3];
        }
        let r = regs();
        r.ccr(0).write_value(now.wrapping_add(10));
        r.dier().modify(|w| w.set_ccie(0, true));
        DONE.wait().await
    }

    fn clear(&mut self) {
        regs().dier().modify(|w| w.set_ccie(0, false));
        STATE.lock(|s| {
            for ax in s.borrow_mut().axes.iter_mut() {
                ax.queue.clear();
                ax.active = false;
            }
        });
    }
}
