//! Stage control: exact STEP pin sequences from the executor, DIR set up before
//! the first STEP and pulse widths against a mocked clock, schedules within one
//! timer tick of the analytical trapezoid, and no motion beyond a soft limit
//! under random command sequences.

use embedded_hal::digital::{ErrorType, InputPin};
use embedded_hal_async::delay::DelayNs;
use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as Pin};
use futures::executor::block_on;
use gonio::cli::in_process::Simulated;
use gonio_acquire::client::HeadClient;
use gonio_firmware::config::REFERENCE;
use gonio_firmware::hw::{Board, Hardware, QueueFull, StepBlock, StepTimer};
use gonio_firmware::motion::blocks::profile_blocks;
use gonio_firmware::motion::executor::Executor;
use gonio_firmware::motion::{move_by, trapezoid, Position};
use gonio_firmware::units;
use gonio_shared::icd::{HomeEndpoint, HomeRequest, MoveEndpoint, StatusEndpoint};
use gonio_shared::{Axis, Geometry};
use gonio_tests::doubles::{FixedClock, ScriptedAdc};
use gonio_tests::step_log::{executor, run, LogPin, Scope};
use proptest::prelude::*;
use std::convert::Infallible;
use std::marker::PhantomData;

const TICK_NS: u64 = 1_000;

fn block(count: u32, interval_ticks: u64) -> StepBlock {
    StepBlock {
        interval: interval_ticks << 32,
        count,
        add: 0,
    }
}

#[test]
fn the_executor_emits_exactly_the_queued_steps_on_each_pin() {
    let high_low = |n| {
        (0..n)
            .flat_map(|_| [Pin::set(State::High), Pin::set(State::Low)])
            .collect::<Vec<_>>()
    };
    let pins = [PinMock::new(&high_low(3)), PinMock::new(&[]), PinMock::new(&high_low(2))];
    let mut exec = Executor::new(pins, 3);
    exec.push(Axis::Rotation, block(3, 10)).unwrap();
    exec.push(Axis::Arm, block(2, 7)).unwrap();
    let mut now = 0;
    let mut next = exec.start();
    while let Some(t) = next {
        now = t;
        next = exec.fire(t);
    }
    assert_eq!(exec.emitted(), [3, 0, 2]);
    // Last step of the rotation at tick 30, its pulse ends 3 ticks later.
    assert_eq!(now, 33);
    assert_eq!(exec.collisions(), 0);
    let mut exec = exec;
    exec.clear();
    // The pins are inside the executor: check them through a fresh start.
    assert_eq!(exec.start(), None);
    // embedded-hal-mock requires done() on every mock.
    drop_and_check(exec);
}

fn drop_and_check(exec: Executor<PinMock>) {
    let mut pins = exec.into_pins();
    for p in pins.iter_mut() {
        p.done();
    }
}

/// A board whose pins log against a clock in nanoseconds and whose delay
/// advances that clock, with the step timer `S`.
struct Scoped<S>(PhantomData<S>);

struct Open;

impl ErrorType for Open {
    type Error = Infallible;
}

impl InputPin for Open {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(false)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(true)
    }
}

struct ScopeDelay(Scope);

impl DelayNs for ScopeDelay {
    async fn delay_ns(&mut self, ns: u32) {
        self.0.clock.set(self.0.clock.get() + ns as u64);
    }
}

struct ScopeSteps {
    exec: Executor<LogPin>,
    scope: Scope,
}

impl StepTimer for ScopeSteps {
    const TICK_HZ: u32 = 1_000_000;
    fn push(&mut self, axis: Axis, b: StepBlock) -> Result<(), QueueFull> {
        self.exec.push(axis, b)
    }
    fn start(&mut self) {
        let origin = self.scope.clock.get();
        run(&mut self.exec, &self.scope, origin, TICK_NS, 0);
    }
    async fn finished(&mut self) -> [u32; 3] {
        self.exec.emitted()
    }
    fn emitted(&self) -> [u32; 3] {
        self.exec.emitted()
    }
    fn brake(&mut self, _: [f32; 3]) {}
    fn clear(&mut self) {
        self.exec.clear();
    }
}

impl<S: StepTimer> Board for Scoped<S> {
    type Out = LogPin;
    type In = Open;
    type Adc = ScriptedAdc;
    type Steps = S;
    type Delay = ScopeDelay;
    type Clock = FixedClock;
}

fn hardware<S: StepTimer>(scope: &Scope, steps: S) -> Hardware<Scoped<S>> {
    Hardware {
        dir: [0, 1, 2].map(|i| scope.pin("dir", i)),
        enable_n: [0, 1, 2].map(|i| scope.pin("enable_n", i)),
        home: [Open, Open, Open],
        gain: [0, 1].map(|i| scope.pin("gain", i)),
        laser: scope.pin("laser", 0),
        adc: ScriptedAdc::default(),
        steps,
        delay: ScopeDelay(scope.clone()),
        clock: FixedClock,
    }
}

#[test]
fn dir_is_set_up_before_the_first_step_and_pulses_have_their_width() {
    let scope = Scope::default();
    let pulse = units::step_pulse_ticks(&REFERENCE.driver, 1_000_000);
    let steps = ScopeSteps {
        exec: executor(&scope, pulse),
        scope: scope.clone(),
    };
    let mut hw = hardware(&scope, steps);
    let mut pos = Position::default();
    let speeds = REFERENCE.axes.map(|a| a.max_speed_dps);
    block_on(move_by(&mut hw, &REFERENCE, &mut pos, [5, 0, -3], speeds)).unwrap();
    assert_eq!(pos.steps, [5, 0, -3]);

    let setup_ns = units::seconds_to_ns(REFERENCE.driver.dir_setup_s) as u64;
    let edges = scope.edges.borrow().clone();
    let dir = |i| edges.iter().find(|e| e.pin == "dir" && e.index == i).copied().unwrap();
    assert!(dir(0).high && !dir(2).high, "DIR follows the sign of the move");
    assert!(
        edges.iter().all(|e| e.pin != "dir" || e.index != 1),
        "an axis that does not move keeps its DIR"
    );
    for (axis, n) in [(0, 5), (2, 3)] {
        let rises = scope.rises("step", axis);
        assert_eq!(rises.len(), n);
        assert!(
            rises[0] >= dir(axis).at + setup_ns,
            "first STEP {} ns after DIR",
            rises[0] - dir(axis).at
        );
        assert!(scope.widths("step", axis).iter().all(|&w| w == pulse * TICK_NS));
        // Driver enabled (active low) before the first step.
        let en = edges.iter().find(|e| e.pin == "enable_n" && e.index == axis).unwrap();
        assert!(!en.high && en.at <= rises[0]);
    }
    assert!(scope.rises("step", 1).is_empty());
    // DIR held after the last STEP edge before anything else may happen.
    let last_fall = edges.iter().filter(|e| e.pin == "step" && !e.high).map(|e| e.at).max().unwrap();
    let hold_ns = units::seconds_to_ns(REFERENCE.driver.dir_hold_s) as u64;
    assert_eq!(scope.clock.get(), last_fall + hold_ns);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Every STEP edge within one tick of the analytical trapezoid.
    #[test]
    fn schedules_stay_within_a_tick_of_the_trapezoid(axis in 0usize..3, n in 1u32..60_000, speed in 0.02f32..1.0) {
        let c = &REFERENCE.axes[axis];
        let t = trapezoid(c, n, speed * c.max_speed_dps);
        let scope = Scope::default();
        let mut exec = executor(&scope, 3);
        prop_assert!(profile_blocks(&t, 1_000_000, |b| exec.push(Axis::ALL[axis], b).is_ok()));
        run(&mut exec, &scope, 0, 1, 0);
        let rises = scope.rises("step", axis);
        prop_assert_eq!(rises.len(), n as usize);
        for (k, tick) in rises.iter().enumerate() {
            let want = t.step_time(k as u32 + 1) * 1e6;
            prop_assert!((*tick as f64 - want).abs() <= 1.0, "step {} at {} vs {}", k + 1, tick, want);
        }
    }
}

fn command() -> impl Strategy<Value = Geometry> {
    prop_oneof![
        // Mostly reachable geometries...
        4 => (0f32..89.0, 0f32..89.0, -180f32..180.0).prop_map(|(a, b, c)| Geometry::new(a, b, c)),
        // ...and some that are not, or are nonsense.
        1 => (-400f32..400.0, -400f32..400.0, -1000f32..1000.0).prop_map(|(a, b, c)| Geometry::new(a, b, c)),
        1 => Just(Geometry::new(f32::NAN, 10.0, 0.0)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// Random command sequences on the simulated head: whatever is accepted or
    /// refused, no axis is ever found beyond its soft limits.
    #[test]
    fn no_axis_leaves_its_soft_limits(cmds in proptest::collection::vec(command(), 1..12)) {
        let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
        rt.block_on(async {
            let head = HeadClient::connect(&Simulated::default()).await.unwrap();
            head.request::<HomeEndpoint>(&HomeRequest::ALL).await.unwrap();
            for g in cmds {
                let _ = head.request::<MoveEndpoint>(&g).await;
                let a = head.request::<StatusEndpoint>(&()).await.unwrap().axes;
                for (axis, deg) in [(0, a.omega_deg), (1, a.tau_deg), (2, a.psi_deg)] {
                    let c = &REFERENCE.axes[axis];
                    assert!(deg >= c.min_deg && deg <= c.max_deg, "axis {axis} at {deg}° after {g:?}");
                }
            }
            head.close().await;
        });
    }
}

/// A step timer whose interrupt never reports the end of a move.
struct Stuck;

impl StepTimer for Stuck {
    const TICK_HZ: u32 = 1_000_000;
    fn push(&mut self, _: Axis, _: StepBlock) -> Result<(), QueueFull> {
        Ok(())
    }
    fn start(&mut self) {}
    async fn finished(&mut self) -> [u32; 3] {
        std::future::pending().await
    }
    fn emitted(&self) -> [u32; 3] {
        [0; 3]
    }
    fn brake(&mut self, _: [f32; 3]) {}
    fn clear(&mut self) {}
}

#[test]
fn a_move_that_never_ends_is_a_stall_fault() {
    let scope = Scope::default();
    let mut hw = hardware(&scope, Stuck);
    let mut pos = Position::default();
    let speeds = REFERENCE.axes.map(|a| a.max_speed_dps);
    let r = block_on(move_by(&mut hw, &REFERENCE, &mut pos, [0, 800, 0], speeds));
    assert_eq!(r, Err(gonio_shared::Fault::StepTimer(Axis::Cradle)));
    assert_eq!(pos.steps, [0, 0, 0]);
}
