//! Hardware doubles for driving the firmware core in tests: `embedded-hal-mock`
//! pins and delays (every transaction checked), a step timer that records what
//! it is given, and an ADC that replays scripted periods.

use embedded_hal_mock::eh1::delay::CheckedDelay;
use embedded_hal_mock::eh1::digital::Mock as PinMock;
use gonio_firmware::hw::{AdcStream, Board, ChopTiming, Clock, Hardware, Overrun, QueueFull, StepBlock, StepTimer};
use gonio_shared::Axis;
use std::collections::VecDeque;

pub struct MockBoard;

impl Board for MockBoard {
    type Out = PinMock;
    type In = PinMock;
    type Adc = ScriptedAdc;
    type Steps = RecordingSteps;
    type Delay = CheckedDelay;
    type Clock = FixedClock;
}

/// Records every run as the blocks queued per axis; emits them all at once
/// (so there is never a move left to brake).
#[derive(Default)]
pub struct RecordingSteps {
    queued: Vec<(Axis, StepBlock)>,
    pub runs: Vec<Vec<(Axis, StepBlock)>>,
}

impl RecordingSteps {
    /// Steps emitted on `axis` over all runs.
    pub fn steps(&self, axis: Axis) -> u32 {
        self.runs.iter().flatten().filter(|(a, _)| *a == axis).map(|(_, b)| b.count).sum()
    }
}

impl StepTimer for RecordingSteps {
    const TICK_HZ: u32 = 1_000_000;

    fn push(&mut self, axis: Axis, block: StepBlock) -> Result<(), QueueFull> {
        self.queued.push((axis, block));
        Ok(())
    }

    fn start(&mut self) {
        self.runs.push(std::mem::take(&mut self.queued));
    }

    async fn finished(&mut self) -> [u32; 3] {
        self.emitted()
    }

    fn emitted(&self) -> [u32; 3] {
        let mut n = [0u32; 3];
        for (a, b) in self.runs.last().into_iter().flatten() {
            n[a.index()] += b.count;
        }
        n
    }

    fn brake(&mut self, _: [f32; 3]) {}

    fn clear(&mut self) {
        self.queued.clear();
    }
}

/// Replays scripted chop periods; an empty script reads as an overrun.
#[derive(Default)]
pub struct ScriptedAdc {
    pub periods: VecDeque<Vec<u16>>,
    pub started: Vec<ChopTiming>,
    pub stops: usize,
}

/// The timer clock the scripted ADC counts (the reference clock tree's).
pub const SCRIPTED_TIMER_HZ: u32 = 84_000_000;

impl AdcStream for ScriptedAdc {
    fn timer_hz(&self) -> u32 {
        SCRIPTED_TIMER_HZ
    }

    const BITS: u8 = 12;

    fn start(&mut self, timing: ChopTiming) {
        self.started.push(timing);
    }

    fn stop(&mut self) {
        self.stops += 1;
    }

    async fn next_period(&mut self, out: &mut [u16]) -> Result<(), Overrun> {
        let p = self.periods.pop_front().ok_or(Overrun)?;
        for (o, c) in out.iter_mut().zip(p.iter().chain(std::iter::repeat(&0))) {
            *o = *c;
        }
        Ok(())
    }
}

pub struct FixedClock;

impl Clock for FixedClock {
    fn now_us(&self) -> u64 {
        0
    }
}

/// A chop period of `m` codes: `high` while the laser is on (first half), `low` after.
pub fn chop_period(m: usize, low: u16, high: u16) -> Vec<u16> {
    (0..m).map(|k| if k < m / 2 { high } else { low }).collect()
}

/// The pins of a `Hardware`, each with its expected transactions.
pub struct Pins {
    pub dir: [PinMock; 3],
    pub enable_n: [PinMock; 3],
    pub home: [PinMock; 3],
    pub gain: [PinMock; 2],
    pub laser: PinMock,
}

impl Pins {
    /// Every pin expecting nothing.
    pub fn idle() -> Self {
        let none = || PinMock::new(&[]);
        Pins {
            dir: [none(), none(), none()],
            enable_n: [none(), none(), none()],
            home: [none(), none(), none()],
            gain: [none(), none()],
            laser: none(),
        }
    }

    pub fn into_hardware(self, delay: CheckedDelay) -> Hardware<MockBoard> {
        Hardware {
            dir: self.dir,
            enable_n: self.enable_n,
            home: self.home,
            gain: self.gain,
            laser: self.laser,
            adc: ScriptedAdc::default(),
            steps: RecordingSteps::default(),
            delay,
            clock: FixedClock,
        }
    }
}

/// Gives a pin of [`Pins::idle`] its expected transactions (the idle mock it
/// replaces is closed, as every mock must be).
pub fn expect(pin: &mut PinMock, transactions: &[embedded_hal_mock::eh1::digital::Transaction]) {
    std::mem::replace(pin, PinMock::new(transactions)).done();
}

/// Checks that every mock saw exactly its expected transactions.
pub fn done(hw: &mut Hardware<MockBoard>) {
    for p in hw
        .dir
        .iter_mut()
        .chain(hw.enable_n.iter_mut())
        .chain(hw.home.iter_mut())
        .chain(hw.gain.iter_mut())
    {
        p.done();
    }
    hw.laser.done();
    hw.delay.done();
}
