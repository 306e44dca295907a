//! The probes. Each measured stretch is bracketed by `mark(name, BEGIN)` and
//! `mark(name, END)`; the emulator records the instructions in between for
//! every bracket and reports the largest per name. A bracket named
//! `overhead` measures the marks themselves, which the emulator subtracts.

use core::convert::Infallible;
use core::hint::black_box;
use cortex_m_rt::entry;
use defmt_rtt as _;
use static_cell::StaticCell;
// The vector table (the image is the chip's: cortex-m-rt wants its interrupts).
use embassy_stm32 as _;
use embedded_hal::digital::{ErrorType, OutputPin};
use gonio_firmware::config::REFERENCE;
use gonio_firmware::demod::{Design, Integrator, Reference};
use gonio_firmware::dispatch;
use gonio_firmware::head::HeadInfo;
use gonio_firmware::kinematics;
use gonio_firmware::motion::blocks::ProfileBlocks;
use gonio_firmware::motion::executor::Executor;
use gonio_firmware::motion::step_irq::{self, CompareTimer};
use gonio_firmware::motion::{self, trapezoid, Position};
use gonio_firmware::sanity::geometry::FixedGeometry;
use gonio_firmware::sanity::model::FixedModel;
use gonio_firmware::sweep;
use gonio_firmware::units;
use gonio_firmware::Head;
use gonio_shared::icd::{HomeEndpoint, HomeRequest, SanityEndpoint, ScanEndpoint, ScanEventTopic, StatusEndpoint, VisitEndpoint};
use gonio_shared::wire::check;
use gonio_shared::{
    AngleRange, Axis, Geometry, Reference as Kind, SanityConfig, SanityModel, ScanEvent, ScanSpec, SweepLobe, SweepRequest, SweepScan,
    Visit, VisitChunk, VISIT_CHUNK, VISIT_QUEUE,
};
use postcard_rpc::header::{VarHeader, VarKey, VarKeyKind, VarSeq};
use postcard_rpc::{Endpoint, Topic};

#[path = "board.rs"]
mod board;

const BEGIN: u32 = 0;
const END: u32 = 1;
const VALUE: u32 = 2;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    mark("panic", BEGIN);
    cortex_m::asm::udf()
}

/// Where the emulator hooks: `name` is read from the image's memory;
/// `phase` says what the call is: [`BEGIN`] or [`END`] of a stretch, or
/// [`VALUE`], a figure the image computed itself (`value`). One function for
/// all three: the linker folds functions with identical bodies into one.
#[inline(never)]
#[no_mangle]
extern "C" fn cost_mark(name: *const u8, len: usize, phase: u32, value: u32) {
    black_box((name, len, phase, value));
}

pub(crate) fn mark(name: &'static str, phase: u32) {
    cost_mark(name.as_ptr(), name.len(), phase, 0);
}

fn report(name: &'static str, value: u32) {
    cost_mark(name.as_ptr(), name.len(), VALUE, value);
}

/// Runs `f` as one measured stretch named `name`.
pub(crate) fn measure<R>(name: &'static str, f: impl FnOnce() -> R) -> R {
    mark(name, BEGIN);
    let r = black_box(f());
    mark(name, END);
    r
}

/// A STEP pin that costs what a GPIO write costs: one store to a BSRR-like
/// word (the chip's `Output::set_high` is a single `str`).
struct StorePin(&'static str);

static mut GPIO_BSRR: u32 = 0;

impl ErrorType for StorePin {
    type Error = Infallible;
}

impl OutputPin for StorePin {
    fn set_high(&mut self) -> Result<(), Infallible> {
        // SAFETY: a plain volatile store to a static the probe owns; one core.
        unsafe { core::ptr::write_volatile(&raw mut GPIO_BSRR, self.0.len() as u32) };
        Ok(())
    }
    fn set_low(&mut self) -> Result<(), Infallible> {
        // SAFETY: as above.
        unsafe { core::ptr::write_volatile(&raw mut GPIO_BSRR, (self.0.len() as u32) << 16) };
        Ok(())
    }
}

/// TIM5's counter, compare and flags as plain words: a register access
/// costs what a store or load to memory costs.
struct MemoryTimer;

static mut TIM_WORDS: [u32; 4] = [0; 4];

impl CompareTimer for MemoryTimer {
    fn count(&self) -> u32 {
        // SAFETY: volatile access to a static the probe owns; one core.
        let c = unsafe { core::ptr::read_volatile(&raw const TIM_WORDS[0]) };
        // The counter runs: each read finds it one tick on.
        unsafe { core::ptr::write_volatile(&raw mut TIM_WORDS[0], c.wrapping_add(1)) };
        c
    }
    fn set_compare(&mut self, at: u32) {
        // SAFETY: as above.
        unsafe { core::ptr::write_volatile(&raw mut TIM_WORDS[1], at) };
    }
    fn clear_match(&mut self) {
        // SAFETY: as above.
        unsafe { core::ptr::write_volatile(&raw mut TIM_WORDS[2], 0) };
    }
    fn enable_interrupt(&mut self, on: bool) {
        // SAFETY: as above.
        unsafe { core::ptr::write_volatile(&raw mut TIM_WORDS[3], on as u32) };
    }
}

fn set_counter(t: u32) {
    // SAFETY: as above.
    unsafe { core::ptr::write_volatile(&raw mut TIM_WORDS[0], t) };
}

/// Queues on `exec` (emptied first) a three-axis move at the axes' cruise
/// speeds (acceleration, cruise and deceleration), its blocks planned as a
/// move plans them (`move_plan`). One executor serves every probe: its
/// queues take 28 KiB.
fn queue_move(exec: &mut Executor<StorePin>) {
    exec.clear();
    mark("move_plan", BEGIN);
    for axis in Axis::ALL {
        let cfg = &REFERENCE.axes[axis.index()];
        // Long enough to reach cruise: v²/a degrees plus a cruise stretch.
        let deg = cfg.max_speed_dps * cfg.max_speed_dps / cfg.max_accel_dps2 + 0.5;
        let n = units::deg_to_steps(cfg, deg) as u32;
        let t = trapezoid(cfg, n, cfg.max_speed_dps);
        let mut blocks = ProfileBlocks::new(&t, TICK_HZ);
        while let Some(b) = measure("move_block", || blocks.next()) {
            let _ = exec.push(axis, b);
        }
    }
    mark("move_plan", END);
}

const TICK_HZ: u32 = 1_000_000;

/// Every event of a move, one measured stretch per `Executor::fire`
/// (`step_event`), then the same move again through the interrupt's logic
/// in a critical section, as TIM5's handler runs it (`step_isr`), braked
/// half-way (`step_isr_braking`: the brake's f32 steps).
#[inline(never)]
fn step_events() {
    let pulse = units::step_pulse_ticks(&REFERENCE.driver, TICK_HZ);
    let mut exec = Executor::new([StorePin("a"), StorePin("bb"), StorePin("ccc")], pulse);
    queue_move(&mut exec);
    let mut next = exec.start();
    while let Some(t) = next {
        next = measure("step_event", || exec.fire(t));
    }
    black_box(exec.emitted());

    for (name, mut brake_at) in [("step_isr", None), ("step_isr_braking", Some(300_000u64))] {
        queue_move(&mut exec);
        set_counter(0);
        let first = exec.start();
        let mut done = step_irq::schedule(&mut exec, &mut MemoryTimer, 0, first);
        let brake = [0, 1, 2].map(|i| units::brake_ticks(&REFERENCE.axes[i], TICK_HZ));
        while done.is_none() {
            // SAFETY: as in MemoryTimer.
            let compare = unsafe { core::ptr::read_volatile(&raw const TIM_WORDS[1]) };
            set_counter(compare);
            if brake_at.is_some_and(|b| compare as u64 >= b) {
                brake_at = None;
                let next = exec.brake(brake);
                done = step_irq::schedule(&mut exec, &mut MemoryTimer, 0, next);
                if done.is_some() {
                    break;
                }
            }
            done = measure(name, || {
                cortex_m::interrupt::free(|_| step_irq::on_compare(&mut exec, &mut MemoryTimer, 0))
            });
        }
        report(name, done.map_or(0, |e| e.iter().sum()));
    }
}

/// Inverse kinematics over the reachable Belcour grid's first incidence.
#[inline(never)]
fn inverse() {
    let spec = ScanSpec::belcour();
    for i in (0..spec.len() / 3).step_by(7) {
        if let Some(g) = spec.point(i) {
            let _ = measure("inverse", || kinematics::inverse(&REFERENCE, &g));
        }
    }
}

/// The head's next point of a scan: the index from the plan's queue, its
/// geometry and its stage targets, over the Belcour grid with its lobe
/// patterns (a ring point's geometry is a few f64 trigonometric calls) and
/// over a 4 096-point incidence (`plan_next`); the order is the host's, so
/// the cost does not grow with the incidence.
#[inline(never)]
fn plan_next() {
    let big = ScanSpec {
        theta_i_deg: heapless::Vec::from_slice(&[30.0]).unwrap_or_default(),
        theta_o: AngleRange::new(0.0, 89.0, 89.0 / 63.0),
        dphi: AngleRange::new(-180.0, 180.0, 360.0 / 63.0),
        first_order: 0,
        sweep: None,
        patterns: None,
    };
    for spec in [ScanSpec::belcour_with_patterns(), big] {
        let mut queue: heapless::Deque<u32, VISIT_QUEUE> = heapless::Deque::new();
        for o in (0..spec.len()).step_by(13) {
            let _ = queue.push_back(spec.index_at_order(o).unwrap_or(0));
            measure("plan_next", || {
                let g = queue.pop_front().and_then(|i| spec.point(i))?;
                let axes = kinematics::inverse(&REFERENCE, &g).ok()?;
                Some(motion::target_steps(&REFERENCE, &axes))
            });
        }
    }
}

/// What a sweep pays besides demodulating its periods: its checks before it
/// moves (the path clear of the blind zone and the sample plane, the axes'
/// speeds: once, in one stretch of the serve loop), the design of its
/// samples (once) and the tag of every sample (after its estimate).
/// A path that leaves the sample plane between reachable ends is refused
/// (`sweep_check` is measured on one that is not).
#[inline(never)]
fn sweep_path() {
    let req = SweepRequest {
        from: Geometry::new(30.0, 42.0, 0.0),
        to: Geometry::new(60.0, 75.0, 40.0),
        speed_dps: 4.0,
        periods_per_sample: 8,
    };
    let (Ok(from), Ok(to)) = (kinematics::inverse(&REFERENCE, &req.from), kinematics::inverse(&REFERENCE, &req.to)) else {
        mark("sweep_refused", BEGIN);
        return;
    };
    let checked = measure("sweep_check", || {
        sweep::check(&REFERENCE, req.periods_per_sample, req.speed_dps, None, 230.0)
            .and_then(|()| sweep::check_path(&REFERENCE, &from, &to))
    });
    let (start, end) = (motion::target_steps(&REFERENCE, &from), motion::target_steps(&REFERENCE, &to));
    let delta = [0, 1, 2].map(|i| end[i] - start[i]);
    let speeds = measure("sweep_limits", || sweep::limits(&REFERENCE, delta, req.speed_dps));
    if checked.is_err() || speeds.is_err() {
        mark("sweep_refused", BEGIN);
        return;
    }
    // A sweep scan's row in place of the inverse kinematics: which row its
    // index is (where it meets the horizon, its rows turned evenly about the
    // laser), its ends, their stage targets, the arm's limits and its
    // stretches across a narrow lobe, in the first turn of the row; then the
    // blocks of its move (`move_block`), slowed down across the lobes.
    let swept = ScanSpec {
        sweep: Some(SweepScan {
            speed_dps: 30.0,
            periods_per_sample: 8,
            lobe: Some(SweepLobe {
                width_deg: 1.8,
                extent_fraction: 0.25,
            }),
        }),
        ..ScanSpec::belcour()
    };
    // Rows turned −180° at θi 15°, 90° and 180° at 30°, 10° and −120° at
    // 60° (the retro point and 37 rows an incidence; the last two meet the
    // horizon at 5.0° and −139.1°): the ends of the span, which take no
    // trigonometry to place, a row between, and the longest rows across the
    // mirror lobe.
    for index in [1, 66, 75, 96, 83] {
        let planned = black_box(measure("sweep_row", || match swept.visit(index, 0) {
            Some(Visit::Row(row)) => sweep::row_plan(&REFERENCE, &row, 230.0).ok(),
            _ => None,
        }));
        if let Some(p) = planned {
            let arm = Axis::Arm.index();
            let t = motion::ramp(&REFERENCE.axes[arm], p.delta()[arm].unsigned_abs(), p.limits[arm], &p.levels);
            let mut blocks = ProfileBlocks::new(&t, TICK_HZ);
            while black_box(measure("move_block", || blocks.next())).is_some() {}
        }
    }
    let design = measure("design_8_periods", || Design::new(8, 230.0));
    // The end of a sample: the estimate of its periods (in two stretches,
    // as the detector yields between them).
    let codes = chopped();
    let r = Reference::new(Kind::Square, M, None);
    let mut integ = Integrator::with(&r, design);
    for _ in 0..8 {
        integ.push(&codes);
    }
    let drift = measure("sweep_drift", || integ.drift());
    black_box(measure("sweep_estimate", || integ.estimate_with(drift)));
    let pos = Position {
        steps: start,
        homed: [true; 3],
        in_flight: Some(delta.map(|d| d.signum() as i8)),
    };
    for k in 0..16u32 {
        let first = delta.map(|d| d.unsigned_abs() * k / 16);
        let last = delta.map(|d| d.unsigned_abs() * (k + 1) / 16);
        black_box(measure("sweep_tag", || sweep::tag(&REFERENCE, &pos, first, last)));
    }
}

/// A sharp ABC-Retro model, the costliest kind to evaluate.
fn abc_retro(back: bool) -> SanityModel {
    SanityModel::AbcRetro {
        kd: 0.3,
        r0: 0.05,
        ab: 5.0,
        bb: 300.0,
        cb: 1.5,
        ar: 8.0,
        br: 500.0,
        cr: 1.2,
        back,
    }
}

/// The fixed-point sanity model, per sample, over a spread of geometries.
#[inline(never)]
fn sanity() {
    let models: [(&'static str, SanityModel); 4] = [
        ("sanity_lambert", SanityModel::Lambert { kd: 0.8 }),
        (
            "sanity_retro_phong",
            SanityModel::RetroPhong {
                kd: 0.3,
                n: 20.0,
                k1: 0.1,
                k2: 0.2,
                k3: 0.5,
                k4: 2.0,
            },
        ),
        ("sanity_abc_retro_view", abc_retro(false)),
        ("sanity_abc_retro_back", abc_retro(true)),
    ];
    for (name, m) in models {
        let Ok(model) = FixedModel::new(&m) else {
            mark("model_refused", BEGIN);
            continue;
        };
        for k in 0..24u32 {
            let g = Geometry::new(15.0 + (k % 4) as f32 * 15.0, (k * 7 % 85) as f32, -180.0 + (k * 37 % 360) as f32);
            if let Some(fg) = FixedGeometry::from_degrees(&g) {
                measure(name, || model.eval(&fg));
            }
        }
    }
}

/// Codes per chop period of the probes.
const M: usize = 64;

/// One chop period of a chopped signal with an offset and a little ripple.
fn chopped() -> [u16; M] {
    let mut codes = [0u16; M];
    for (k, c) in codes.iter_mut().enumerate() {
        *c = 1800 + if k < M / 2 { 600 } else { 0 } + (k as u16 * 7) % 5;
    }
    codes
}

/// One chop period of M = 64 codes through the integrator (correlation,
/// extremes, the drift and mains nuisance fit), per reference kind.
#[inline(never)]
fn demod() {
    let codes = chopped();
    // The regression's design, as a configure computes it: factored up
    // front for a default integration and for the longest that is.
    let design = measure("design_23_periods", || Design::new(23, 230.0));
    black_box(measure("design_256_periods", || Design::new(256, 230.0)));
    for (name, kind) in [("demod_square", Kind::Square), ("demod_sine", Kind::Sine)] {
        let r = Reference::new(kind, M, None);
        let mut integ = Integrator::with(&r, design.clone());
        for _ in 0..23 {
            measure(name, || integ.push(&codes));
        }
        black_box(integ.estimate());
    }
    // A longer integration accumulates its own Gram matrix, period by period.
    let r = Reference::new(Kind::Square, M, None);
    let mut integ = Integrator::new(&r, 1_000, 230.0);
    for _ in 0..23 {
        measure("demod_long", || integ.push(&codes));
    }
    black_box(integ.estimate());
}

/// A request frame as the link hands it over: checked, its key matched and
/// its body decoded.
#[inline(never)]
fn dispatch_frame() {
    let mut buf = [0u8; 64];
    let Some(n) = dispatch::encode(StatusEndpoint::REQ_KEY, VarKeyKind::Key8, VarSeq::Seq2(7), &(), &mut buf) else {
        mark("encode_failed", BEGIN);
        return;
    };
    for _ in 0..4 {
        let _ = measure("dispatch_decode", || dispatch::decode(&buf[..n]).is_ok());
    }
}

/// A request frame with its check, as the host sends it.
fn request<E: Endpoint>(req: &E::Request) -> heapless::Vec<u8, 256>
where
    E::Request: serde::Serialize,
{
    let mut buf = [0u8; 256];
    let n = dispatch::encode(E::REQ_KEY, VarKeyKind::Key8, VarSeq::Seq2(1), req, &mut buf[..256 - check::LEN]).unwrap_or(0);
    let n = check::seal(&mut buf, n).unwrap_or(0);
    heapless::Vec::from_slice(&buf[..n]).unwrap_or_default()
}

/// The visit order from `from`, a chunk's worth (the serpentine: the head
/// takes any order; the host's plan only changes which moves it makes).
fn chunk(spec: &ScanSpec, from: u32) -> heapless::Vec<u8, 256> {
    let indices = (from..spec.len().min(from + VISIT_CHUNK as u32))
        .filter_map(|o| spec.index_at_order(o))
        .collect();
    request::<VisitEndpoint>(&VisitChunk {
        run: 0,
        first_order: from,
        indices,
    })
}

/// What the head said, read between polls (outside the measured stretches):
/// points done, and whether the scan has finished.
fn look(done: &mut u32) -> bool {
    let mut finished = false;
    for f in board::HOST.outbox.borrow_mut().drain(..) {
        let Some((hdr, body)) = check::open(&f).and_then(VarHeader::take_from_slice) else {
            continue;
        };
        if hdr.key != VarKey::Key8(ScanEventTopic::TOPIC_KEY) {
            continue;
        }
        match postcard::from_bytes::<ScanEvent>(body) {
            Ok(ScanEvent::Sample(_) | ScanEvent::Skipped { .. }) => *done += 1,
            Ok(ScanEvent::Finished { .. } | ScanEvent::Stopped { .. }) => finished = true,
            _ => {}
        }
    }
    finished
}

/// Serves `spec` from `spec.first_order` (already started when `started`),
/// feeding its plan as the host does; every poll of the serve loop is a
/// measured stretch (`await_free`).
fn serve(head: &mut Head<board::Rigged>, spec: &ScanSpec, started: bool, mut fed: u32, points: &'static str) {
    let mut inbox = board::HOST.inbox.borrow_mut();
    if !started {
        let _ = inbox.push_back(request::<ScanEndpoint>(spec));
    }
    drop(inbox);
    board::HOST.closed.set(false);
    let mut done = spec.first_order;
    let (mut link, mut sentry) = (board::Script, board::Calm);
    let (link, sentry) = (&mut link, &mut sentry);
    let mut idle = 0;
    board::run_in_arena(
        "await_free",
        move || head.serve(link, sentry),
        || {
            let before = done;
            if look(&mut done) {
                board::HOST.closed.set(true);
            }
            // A head that neither measures nor finishes has stopped the scan
            // for a reason the figures would hide: end the image there.
            idle = if done == before { idle + 1 } else { 0 };
            if idle > 100_000 {
                mark("serve_stalled", BEGIN);
            }
            if !board::HOST.closed.get() && fed < spec.len() && fed - done <= (VISIT_QUEUE - VISIT_CHUNK) as u32 {
                let mut inbox = board::HOST.inbox.borrow_mut();
                if inbox.push_back(chunk(spec, fed)).is_ok() {
                    fed = (fed + VISIT_CHUNK as u32).min(spec.len());
                }
            }
            false
        },
    );
    report(points, done - spec.first_order);
}

/// The head the scan probes serve, in a static as the chip's task arena
/// holds it, made in a frame of its own: the head passes through
/// the stack on its way there, and that frame is gone before the scan runs.
#[inline(never)]
fn probe_head(info: HeadInfo) -> &'static mut Head<board::Rigged> {
    static HEAD: StaticCell<Head<board::Rigged>> = StaticCell::new();
    HEAD.init(Head::new(REFERENCE, board::hardware(), info))
}

/// A Belcour scan served, with a sanity model loaded (the costliest
/// kind), then a resume near its end: the start of the resumed scan with its
/// first chunk measured on its own (`resume`), and its points served.
#[inline(never)]
fn scan_and_resume() {
    board::place_near_home(3.0);
    let info = HeadInfo {
        board: "probe",
        serial: heapless::String::new(),
        simulated: true,
        protocol_version: gonio_shared::PROTOCOL_VERSION,
    };
    let head = probe_head(info);
    head.prepare();
    let sanity = SanityConfig {
        model: abc_retro(true),
        current_a_per_sr_inv: 1.0e-7,
        splitter_factor: 0.5,
        rel_tol: 0.5,
        abs_tol_v: 0.01,
        k_noise: 3.0,
        remeasure: false,
    };
    {
        let mut inbox = board::HOST.inbox.borrow_mut();
        let _ = inbox.push_back(request::<HomeEndpoint>(&HomeRequest::ALL));
        let _ = inbox.push_back(request::<SanityEndpoint>(&sanity));
    }
    // Belcour's grid, all of its 3 441 points.
    let spec = ScanSpec::belcour();
    serve(head, &spec, false, 0, "scan_points");

    let resumed = ScanSpec {
        first_order: spec.len() - 2 * VISIT_CHUNK as u32,
        ..spec
    };
    let first = VisitChunk {
        run: 0,
        first_order: resumed.first_order,
        indices: (resumed.first_order..resumed.first_order + VISIT_CHUNK as u32)
            .filter_map(|o| resumed.index_at_order(o))
            .collect(),
    };
    let started = measure("resume", || {
        head.start_scan(resumed.clone()).and_then(|_| head.queue_visits(&first))
    });
    if started.is_err() {
        mark("resume_refused", BEGIN);
    }
    serve(head, &resumed, true, resumed.first_order + VISIT_CHUNK as u32, "resume_points");
}

// Every probe is out of line (`#[inline(never)]`): inlined here, their
// locals would share one frame, more than the 64 KiB stack.
#[entry]
fn main() -> ! {
    for _ in 0..8 {
        measure("overhead", || ());
    }
    step_events();
    inverse();
    sanity();
    demod();
    dispatch_frame();
    plan_next();
    sweep_path();
    scan_and_resume();
    mark("done", BEGIN);
    loop {
        cortex_m::asm::bkpt();
    }
}
