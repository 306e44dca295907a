//! The head: owns the hardware and the state, answers commands, runs scans.
//!
//! Requests are served one at a time in arrival order. A scan is accepted at
//! once and then advanced one point per loop turn; between points the head
//! looks for waiting requests, so status and abort are answered mid-scan.
//! Every change of what the head does goes through the state table
//! ([`crate::state`]) in [`Head::apply`].

use crate::config::HeadConfig;
use crate::conversation::Conversation;
use crate::detector::Detector;
use crate::hw::{Board, Clock, Hardware, StepTimer};
use crate::kinematics;
use crate::motion::{self, Position};
use crate::sanity::geometry::FixedGeometry;
use crate::sanity::Sanity;
use crate::scan_run::ScanRun;
use crate::state::{self, Drivers, Event, Laser, Mode};
use crate::sweep::Sweeping;
use crate::{homing, sweep, units};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::icd::{HomeRequest, MeasureRequest, MoveReport};
use gonio_shared::sample::ScanPosition;
use gonio_shared::{
    Axis, AxisAngles, CalibrateRequest, CalibrationReport, Capabilities, DetectionSettings, Fault, Field, Geometry, HeadState, Identity,
    PlanChunk, PlanQueued, Reply, SafetySettings, Sample, SampleFlags, SanityConfig, ScanAccepted, ScanSpec, Signal, Status, SweepLobe,
    SweepReport, SweepRequest, SweepRow, SweptSample,
};

/// Who this head is; the board and the serial come from the binary.
#[derive(Debug, Clone)]
pub struct HeadInfo {
    pub board: &'static str,
    pub serial: heapless::String<24>,
    pub simulated: bool,
    /// Reported protocol version; the real value except in mismatch tests.
    pub protocol_version: u16,
}

/// Consecutive scan points that may all be saturated at the lowest gain, or
/// all below the noise floor, before the head stops the scan (stray light or
/// a failed amplifier; a dead laser or a blocked beam). A retroreflector's
/// scan has neither run; a black sample needs the dark watch relaxed.
pub const SUSPECT_RUN: u32 = 8;

/// What one turn of a sweep scan's row did.
pub(crate) enum SweepTurn {
    /// The sweep began: the stages move, the chop runs.
    Begun,
    /// A sample; more follow.
    Sample(SweptSample),
    /// The row's last sample, and how many it made.
    Last(SweptSample, u32),
}

/// Runs of suspicious samples in the current scan.
#[derive(Debug, Default, Clone, Copy)]
struct SuspectRuns {
    saturated: u32,
    dark: u32,
}

pub struct Head<B: Board> {
    pub(crate) cfg: HeadConfig,
    pub(crate) hw: Hardware<B>,
    info: HeadInfo,
    pos: Position,
    detector: Detector,
    sanity: Option<Sanity>,
    pub(crate) scan: Option<ScanRun>,
    /// The row a sweep scan is sweeping, between two turns of the serve
    /// loop; any stop ends it (the row is swept again on continuing).
    sweeping: Option<Sweeping>,
    laser_on: bool,
    seq: u32,
    /// What the serve loop keeps of the conversation with the host.
    pub(crate) talk: Conversation,
    samples_flagged: u32,
    samples_remeasured: u32,
    pub(crate) last_fault: Option<Fault>,
    /// What the head is doing (the state table's state).
    pub(crate) mode: Mode,
    drivers_on: bool,
    pub(crate) estop_open: bool,
    /// Host watch and idle times.
    pub(crate) safety: SafetySettings,
    /// When the host was last heard (µs, the head's clock).
    pub(crate) last_heard_us: u64,
    /// When the last operation ended (µs): the idle times count from it.
    pub(crate) rest_since_us: u64,
    suspect: SuspectRuns,
    /// Scan runs started since power-up.
    runs: u32,
}

impl<B: Board> Head<B> {
    pub fn new(cfg: HeadConfig, hw: Hardware<B>, info: HeadInfo) -> Self {
        let mut head = Self {
            cfg,
            hw,
            info,
            pos: Position::default(),
            detector: Detector::new::<B::Adc>(DetectionSettings::default()),
            sanity: None,
            scan: None,
            sweeping: None,
            laser_on: false,
            seq: 0,
            talk: Conversation::default(),
            samples_flagged: 0,
            samples_remeasured: 0,
            last_fault: None,
            mode: Mode::Idle,
            drivers_on: false,
            estop_open: false,
            safety: SafetySettings::default(),
            last_heard_us: 0,
            rest_since_us: 0,
            suspect: SuspectRuns::default(),
            runs: 0,
        };
        head.safe_state();
        head
    }

    /// Reports why the head last restarted (a watchdog reset), in the status.
    pub fn restarted_by(&mut self, f: Fault) {
        self.last_fault = Some(f);
    }

    /// Laser off, conversions stopped, drivers disabled, step queues emptied.
    /// Pin errors are ignored here: there is nothing safer left to do.
    pub fn safe_state(&mut self) {
        self.sweeping = None;
        self.hw.steps.clear();
        self.detector.stop(&mut self.hw);
        let _ = self.hw.laser.set_low();
        self.laser_on = false;
        self.drivers(false);
    }

    /// Laser enable low and the chop stopped, at once.
    fn laser_off(&mut self) {
        let _ = self.hw.laser.set_low();
        self.laser_on = false;
        self.detector.stop(&mut self.hw);
    }

    fn drivers(&mut self, on: bool) {
        for en in self.hw.enable_n.iter_mut() {
            let _ = if on { en.set_low() } else { en.set_high() };
        }
        self.drivers_on = on;
    }

    /// Applies one event of the state table: a refused request changes
    /// nothing; otherwise the laser and the drivers follow the table and the
    /// head takes the new state. The only way the state changes.
    pub(crate) fn apply(&mut self, e: Event) -> Result<(), Fault> {
        let t = state::transition(self.mode, e);
        if let Some(f) = t.refused {
            return Err(f);
        }
        if t.laser == Laser::Off {
            self.laser_off();
        }
        match t.drivers {
            Drivers::Enable => self.drivers(true),
            Drivers::Disable => self.drivers(false),
            Drivers::Keep => {}
        }
        if !t.to.busy() && self.mode.busy() {
            self.rest_since_us = self.hw.clock.now_us();
        }
        self.mode = t.to;
        Ok(())
    }

    /// Ends an operation in the table: done, or failed (safe state). The
    /// idle times count from here (in a pause too).
    fn finish<T>(&mut self, r: Reply<T>) -> Reply<T> {
        self.rest_since_us = self.hw.clock.now_us();
        match &r {
            Ok(_) => {
                let _ = self.apply(Event::Done);
            }
            Err(f) => {
                self.last_fault = Some(*f);
                let _ = self.apply(Event::Failed);
            }
        }
        r
    }

    /// Stops whatever runs after `e` (abort, pause, link loss, host silence,
    /// E-STOP): the laser goes off in the transition, before anything else;
    /// then the motion in flight decelerates from its current speed, its
    /// steps counted in, and the head takes the state the stop asked for.
    pub(crate) async fn stop(&mut self, e: Event) {
        if self.apply(e).is_err() {
            return;
        }
        self.sweeping = None;
        motion::halt(&mut self.hw, &self.cfg, &mut self.pos).await;
        let _ = self.apply(Event::Stopped);
    }

    fn laser(&mut self, on: bool) -> Result<(), Fault> {
        if on && !self.mode.laser_allowed() {
            return Err(Fault::Busy);
        }
        let r = if on { self.hw.laser.set_high() } else { self.hw.laser.set_low() };
        r.map_err(|_| Fault::Gpio)?;
        self.laser_on = on;
        Ok(())
    }

    pub fn identity(&self) -> Identity {
        let d = &self.cfg.detector;
        Identity {
            protocol_version: self.info.protocol_version,
            firmware_version: heapless::String::try_from(env!("CARGO_PKG_VERSION")).unwrap_or_default(),
            board: heapless::String::try_from(self.info.board).unwrap_or_default(),
            serial: self.info.serial.clone(),
            simulated: self.info.simulated,
            capabilities: Capabilities {
                axes: 3,
                gain_ranges: d.gains_v_per_a.len() as u8,
                adc_bits: <B::Adc as crate::hw::AdcStream>::BITS,
                max_scan_incidences: 8,
                gains_v_per_a: d.gains_v_per_a,
            },
        }
    }

    pub fn status(&self) -> Status {
        let (run, next_order, total) = self.scan.as_ref().map_or((0, 0, 0), ScanRun::progress);
        Status {
            state: match self.mode {
                Mode::Idle => HeadState::Idle,
                Mode::Homing => HeadState::Homing,
                Mode::Moving => HeadState::Moving,
                Mode::Measuring => HeadState::Measuring,
                Mode::Scanning => HeadState::Scanning { next_order, total },
                Mode::Paused => HeadState::Paused { run, next_order, total },
                Mode::Stopping(_) => HeadState::Stopping,
                Mode::Faulted => HeadState::Faulted,
            },
            homed: self.pos.all_homed(),
            laser_on: self.laser_on,
            drivers_enabled: self.drivers_on,
            estop_open: self.estop_open,
            axes: self.pos.angles(&self.cfg),
            detection: *self.detector.settings(),
            samples_sent: self.seq,
            samples_flagged: self.samples_flagged,
            samples_remeasured: self.samples_remeasured,
            sanity_loaded: self.sanity.is_some(),
            last_fault: self.last_fault,
            uptime_us: self.hw.clock.now_us(),
        }
    }

    pub async fn home(&mut self, req: HomeRequest) -> Reply<gonio_shared::AxisAngles> {
        self.apply(Event::Home)?;
        let wanted = [req.rotation, req.cradle, req.arm];
        let mut r = Ok(());
        for axis in Axis::ALL {
            if wanted[axis.index()] {
                r = homing::home_axis(&mut self.hw, &self.cfg, &mut self.pos, axis).await;
                if r.is_err() {
                    break;
                }
            }
        }
        if r.is_ok() {
            // The switches sit just outside the travel: park the homed axes at
            // 0° (the retro direction at normal incidence), inside it.
            let park = [0, 1, 2].map(|i| if wanted[i] { motion::PARK[i] } else { self.pos.steps[i] });
            r = motion::move_to(&mut self.hw, &self.cfg, &mut self.pos, park).await;
        }
        if r.is_err() {
            self.safe_state();
        }
        let r = r.map(|_| self.pos.angles(&self.cfg));
        self.finish(r)
    }

    /// Moves to a geometry; refuses before moving when it is unreachable.
    async fn goto(&mut self, g: &Geometry) -> Reply<MoveReport> {
        let axes = kinematics::inverse(&self.cfg, g)?;
        if !self.pos.all_homed() {
            return Err(Fault::NotHomed);
        }
        let t0 = self.hw.clock.now_us();
        let target = motion::target_steps(&self.cfg, &axes);
        if let Err(f) = motion::move_to(&mut self.hw, &self.cfg, &mut self.pos, target).await {
            self.safe_state();
            return Err(f);
        }
        let reached_axes = self.pos.angles(&self.cfg);
        Ok(MoveReport {
            reached: kinematics::forward(&reached_axes),
            axes: reached_axes,
            duration_s: (self.hw.clock.now_us().saturating_sub(t0)) as f32 * 1e-6,
        })
    }

    pub async fn move_to(&mut self, g: Geometry) -> Reply<MoveReport> {
        self.apply(Event::Move)?;
        let r = self.goto(&g).await;
        self.finish(r)
    }

    /// Moves (if asked), settles, and takes one sample with the laser on.
    pub(crate) async fn acquire(&mut self, at: Option<Geometry>, scan: Option<ScanPosition>) -> Reply<Sample> {
        let target = match at {
            Some(g) => {
                // The conversions stop for the move: on the chip the DMA ring
                // (two chop periods) would overrun within milliseconds and
                // lose its alignment with the chop; the next measurement
                // restarts it aligned, and settles first.
                self.detector.stop(&mut self.hw);
                self.goto(&g).await?;
                let settle = units::seconds_to_us(self.detector.settings().settle_s);
                self.hw.delay.delay_us(settle).await;
                g
            }
            None => kinematics::forward(&self.pos.angles(&self.cfg)),
        };
        self.laser(true)?;
        let axes = self.pos.angles(&self.cfg);
        let reached = kinematics::forward(&axes);
        let splitter = kinematics::through_splitter(&self.cfg, &axes);
        let mut m = self.measure_checked(&reached, splitter).await?;
        if m.flags.contains(SampleFlags::OVERRUN) {
            // A lost ADC block breaks the integration's timing: measure again;
            // twice in a row is a fault of the conversion chain.
            m = self.measure_checked(&reached, splitter).await?;
            if m.flags.contains(SampleFlags::OVERRUN) {
                self.safe_state();
                return Err(Fault::AdcOverrun);
            }
        }
        if m.flags.contains(SampleFlags::MODEL_MISMATCH) && self.sanity.as_ref().is_some_and(|s| s.config().remeasure) {
            // Measured once more; the second reading stands, marked as such.
            m = self.measure_checked(&reached, splitter).await?;
            m.flags.insert(SampleFlags::REMEASURED);
            self.samples_remeasured = self.samples_remeasured.wrapping_add(1);
        }
        let mut flags = m.flags;
        if splitter {
            flags.insert(SampleFlags::THROUGH_SPLITTER);
        }
        if flags.doubtful() {
            self.samples_flagged = self.samples_flagged.wrapping_add(1);
        }
        let s = Sample {
            seq: self.seq,
            scan,
            timestamp_us: self.hw.clock.now_us(),
            target,
            reached,
            axes,
            signal: Signal { flags, ..m },
        };
        self.seq = self.seq.wrapping_add(1);
        Ok(s)
    }

    /// One detector reading, checked against the loaded model.
    async fn measure_checked(&mut self, at: &Geometry, through_splitter: bool) -> Reply<Signal> {
        let mut m = match self.detector.measure(&mut self.hw, &self.cfg).await {
            Ok(m) => m,
            Err(f) => {
                self.safe_state();
                return Err(f);
            }
        };
        if self.sanity.is_some() {
            // The estimate, the geometry in fixed point and the model are
            // each a long computation on the chip (up to 85 000 instructions,
            // `chip-bench`): yield between them and after.
            embassy_futures::yield_now().await;
            let fg = FixedGeometry::from_degrees(at);
            embassy_futures::yield_now().await;
            let expected = self
                .sanity
                .as_ref()
                .zip(fg)
                .map(|(s, fg)| (s, s.expected_at(&fg, m.gain_v_per_a, through_splitter)));
            if expected.is_none_or(|(s, e)| s.mismatch(e, m.amplitude_v, m.noise_v)) {
                m.flags.insert(SampleFlags::MODEL_MISMATCH);
            }
            embassy_futures::yield_now().await;
        }
        Ok(m)
    }

    pub async fn measure(&mut self, req: MeasureRequest) -> Reply<Sample> {
        self.apply(Event::Measure)?;
        let r = self.acquire(req.at, None).await;
        self.rest_laser();
        self.finish(r)
    }

    /// Sweeps from `req.from` to `req.to` while the laser chops
    /// ([`SweepRequest`], [`crate::sweep`]): every `periods_per_sample`
    /// periods become one [`SweptSample`], handed to `emit` as it is made.
    /// A sweep refused (an end or the path unreachable, a speed or length
    /// out of range, the head busy or not homed) changes nothing.
    pub async fn sweep(&mut self, req: SweepRequest, mut emit: impl FnMut(SweptSample)) -> Reply<SweepReport> {
        if let Some(f) = state::transition(self.mode, Event::Measure).refused {
            return Err(f);
        }
        let (start, end, limits) = self.sweep_path(&req).await?;
        self.apply(Event::Measure)?;
        let r = async {
            let mut sw = self.begin_sweep(req.periods_per_sample, (limits, &[]), start, end, None).await?;
            while sw.moving {
                emit(self.swept_sample(&mut sw).await?);
            }
            self.end_sweep(sw).await
        }
        .await;
        self.rest_laser();
        self.finish(r)
    }

    /// Checks a sweep and works out its stage targets and axis limits;
    /// changes nothing.
    async fn sweep_path(&mut self, req: &SweepRequest) -> Reply<([i32; 3], [i32; 3], [motion::Limits; 3])> {
        self.check_sweep(req.periods_per_sample, req.speed_dps, None)?;
        // Each inverse is some 45 000 instructions on the chip (`chip-bench`):
        // the executor runs between them.
        let from = kinematics::inverse(&self.cfg, &req.from)?;
        embassy_futures::yield_now().await;
        let to = kinematics::inverse(&self.cfg, &req.to)?;
        embassy_futures::yield_now().await;
        sweep::check_path(&self.cfg, &from, &to)?;
        self.stage_path(&from, &to, req.speed_dps)
    }

    /// The stage targets and axis limits of a sweep between stage angles
    /// `from` and `to` at `speed_dps`, once the head is known to be homed.
    fn stage_path(&self, from: &AxisAngles, to: &AxisAngles, speed_dps: f32) -> Reply<([i32; 3], [i32; 3], [motion::Limits; 3])> {
        if !self.pos.all_homed() {
            return Err(Fault::NotHomed);
        }
        let (start, end) = (motion::target_steps(&self.cfg, from), motion::target_steps(&self.cfg, to));
        let delta = [0, 1, 2].map(|i| end[i] - start[i]);
        Ok((start, end, sweep::limits(&self.cfg, delta, speed_dps)?))
    }

    /// Whether a sweep scan's row is under way (its arm moving, its chop
    /// running).
    pub(crate) fn sweeping(&self) -> bool {
        self.sweeping.is_some()
    }

    /// Checks what a sweep asks of the detector and of its samples.
    fn check_sweep(&self, periods_per_sample: u16, speed_dps: f32, lobe: Option<&SweepLobe>) -> Reply<()> {
        let chop_hz = self.detector.settings().chop_hz;
        sweep::check(&self.cfg, periods_per_sample, speed_dps, lobe, chop_hz)?;
        if chop_hz > SweepRequest::CHOP_MAX_HZ {
            return Err(Fault::InvalidValue(Field::ChopFrequency));
        }
        Ok(())
    }

    /// One turn of a sweep scan's row at scan position `at`: the first turn
    /// works out and begins the sweep (the arm alone moves, at the row's
    /// speed or its limit), every other one takes one sample; the last ends
    /// the sweep. A row refused (beyond the travel) changes nothing.
    pub(crate) async fn sweep_turn(&mut self, row: &SweepRow, at: ScanPosition) -> Reply<SweepTurn> {
        let Some(mut sw) = self.sweeping.take() else {
            self.check_sweep(row.periods_per_sample, row.speed_dps, row.lobe.as_ref())?;
            let p = sweep::row_plan(&self.cfg, row, self.detector.settings().chop_hz)?;
            if !self.pos.all_homed() {
                return Err(Fault::NotHomed);
            }
            self.sweeping = Some(
                self.begin_sweep(row.periods_per_sample, (p.limits, &p.levels), p.start, p.end, Some(at))
                    .await?,
            );
            return Ok(SweepTurn::Begun);
        };
        // Dropped by a stop in the middle of a sample, `sw` ends the sweep.
        let s = self.swept_sample(&mut sw).await?;
        if s.signal.flags.doubtful() {
            self.samples_flagged = self.samples_flagged.wrapping_add(1);
        }
        // The watch of a scan's points, over its samples: a run of
        // saturated ones (8, some 8° of a row at 30 deg/s) ends the scan,
        // and so does a row all of whose samples are below the noise (a
        // dead laser, a blocked beam: a swept sample integrates a third of a
        // point's periods, and a dark floor a few degrees long is no
        // fault); the arm is braked, the sample that completed it not sent.
        sw.lit |= !s.signal.flags.contains(SampleFlags::BELOW_NOISE);
        let watched = self.watch(s.signal.flags.difference(SampleFlags::BELOW_NOISE));
        let row_dark = !sw.moving && !sw.lit;
        if let Err(f) = watched.and(if row_dark { Err(Fault::NoSignal) } else { Ok(()) }) {
            return Err(self.abandon_sweep(f).await);
        }
        if sw.moving {
            self.sweeping = Some(sw);
            return Ok(SweepTurn::Sample(s));
        }
        let report = self.end_sweep(sw).await?;
        Ok(SweepTurn::Last(s, report.samples))
    }

    /// Starts a checked sweep: the move to its start, the settle time, the
    /// design of its samples and the plan of its move (within `limits`, in
    /// its stretches), the laser and the chop (ranged), and the move. A
    /// failure leaves the head safe.
    async fn begin_sweep(
        &mut self,
        periods_per_sample: u16,
        (limits, levels): ([motion::Limits; 3], &[motion::Level]),
        start: [i32; 3],
        end: [i32; 3],
        scan: Option<ScanPosition>,
    ) -> Reply<Sweeping> {
        let r = async {
            self.detector.stop(&mut self.hw);
            // To the start, whose stage targets are known already.
            motion::move_to(&mut self.hw, &self.cfg, &mut self.pos, start).await?;
            self.hw
                .delay
                .delay_us(units::seconds_to_us(self.detector.settings().settle_s))
                .await;
            // Computed and planned before the chop starts: from then on the
            // ADC's ring (two periods) must be read as it fills.
            self.detector.design_sweep(periods_per_sample);
            let delta = [0, 1, 2].map(|i| end[i] - self.pos.steps[i]);
            let run = motion::plan(&mut self.hw, &self.cfg, delta, limits, levels).await?;
            self.laser(true)?;
            self.detector.prepare_sweep(&mut self.hw, &self.cfg).await?;
            motion::start(&mut self.hw, &mut self.pos, &run);
            let t0 = self.hw.clock.now_us();
            Ok(Sweeping {
                run,
                scan,
                t0,
                first: [0; 3],
                start_us: t0,
                moving: true,
                splitter: kinematics::through_splitter(&self.cfg, &self.pos.angles(&self.cfg)),
                lit: false,
                samples: 0,
            })
        }
        .await;
        if r.is_err() {
            self.safe_state();
        }
        r
    }

    /// The next sample of a sweep under way (its last once `sw.moving`
    /// turns false). A stalled move or a lost ADC block stops the sweep and
    /// leaves the head safe.
    async fn swept_sample(&mut self, sw: &mut Sweeping) -> Reply<SweptSample> {
        if self.hw.clock.now_us().saturating_sub(sw.t0) > sw.run.limit_ms as u64 * 1000 {
            let f = sw.run.stalled(&mut self.hw, &mut self.pos);
            self.safe_state();
            return Err(f);
        }
        match self.detector.resettle_moving(&mut self.hw, &self.cfg, &mut sw.moving).await {
            Ok(Some(start)) => (sw.first, sw.start_us) = start,
            Ok(None) => {}
            Err(f) => return Err(self.abandon_sweep(f).await),
        }
        let (mut signal, last, end_us) = match self.detector.measure_moving(&mut self.hw, &self.cfg, &mut sw.moving).await {
            Ok(m) => m,
            Err(f) => return Err(self.abandon_sweep(f).await),
        };
        if sw.splitter {
            signal.flags.insert(SampleFlags::THROUGH_SPLITTER);
        }
        if signal.flags.contains(SampleFlags::OVERRUN) {
            // A lost block breaks the alignment of the ring with the
            // chop for every sample after it: the sweep stops.
            return Err(self.abandon_sweep(Fault::AdcOverrun).await);
        }
        let (axes_from, axes_to) = sweep::tag(&self.cfg, &self.pos, sw.first, last);
        let s = SweptSample {
            seq: self.seq,
            scan: sw.scan,
            start_us: sw.start_us,
            duration_s: end_us.saturating_sub(sw.start_us) as f32 * 1e-6,
            axes_from,
            axes_to,
            signal,
        };
        self.seq = self.seq.wrapping_add(1);
        sw.samples += 1;
        (sw.first, sw.start_us) = (last, end_us);
        Ok(s)
    }

    /// Gives a sweep up for `f` in the middle of its move: the arm braked
    /// from its speed (its steps counted in), the head made safe.
    async fn abandon_sweep(&mut self, f: Fault) -> Fault {
        motion::halt(&mut self.hw, &self.cfg, &mut self.pos).await;
        self.safe_state();
        f
    }

    /// Ends a sweep whose move is over: its steps counted in and checked.
    async fn end_sweep(&mut self, sw: Sweeping) -> Reply<SweepReport> {
        let emitted = self.hw.steps.emitted();
        if let Err(f) = motion::end(&mut self.hw, &self.cfg, &mut self.pos, &sw.run, emitted).await {
            self.safe_state();
            return Err(f);
        }
        Ok(SweepReport {
            samples: sw.samples,
            duration_s: self.hw.clock.now_us().saturating_sub(sw.t0) as f32 * 1e-6,
            reached: kinematics::forward(&self.pos.angles(&self.cfg)),
        })
    }

    /// After a measurement at rest: the chop stops, and the laser goes off
    /// unless it is to stay on for its idle time.
    fn rest_laser(&mut self) {
        self.detector.stop(&mut self.hw);
        if self.safety.laser_idle_s == 0.0 {
            let _ = self.laser(false);
        }
    }

    /// Starts a scan; one held in a pause is replaced (with a `Stopped`
    /// event for it), once the new one is known to be valid.
    pub fn start_scan(&mut self, spec: ScanSpec) -> Reply<ScanAccepted> {
        if let Some(f) = state::transition(self.mode, Event::Scan).refused {
            return Err(f);
        }
        let total = spec.validate()?;
        if let Some(how) = spec.sweep {
            // Every row shares these: refused here, not row by row.
            self.check_sweep(how.periods_per_sample, how.speed_dps, how.lobe.as_ref())?;
        }
        if !self.pos.all_homed() {
            return Err(Fault::NotHomed);
        }
        self.drop_scan(Fault::Aborted);
        self.apply(Event::Scan)?;
        let first_order = spec.first_order;
        self.suspect = SuspectRuns::default();
        self.last_heard_us = self.hw.clock.now_us();
        self.runs = self.runs.wrapping_add(1);
        self.scan = Some(ScanRun::new(self.runs, spec, total));
        Ok(ScanAccepted {
            points: total,
            first_order,
            run: self.runs,
        })
    }

    /// Queues the next stretch of the running or held scan's visit order.
    /// A chunk that does not start where the queue ends takes nothing, and
    /// what does not fit is left out: the answer says where to go on.
    pub fn queue_plan(&mut self, chunk: &PlanChunk) -> Reply<PlanQueued> {
        match self.scan.as_mut().filter(|r| r.is_addressed_by(chunk)) {
            Some(run) => run.queue(chunk),
            None => Err(Fault::NotScanning),
        }
    }

    /// Drops a scan, running or held, with a `Stopped` event for `why`.
    pub(crate) fn drop_scan(&mut self, why: Fault) {
        if let Some(run) = self.scan.take() {
            self.last_fault = Some(why);
            self.talk.pending_event = Some(run.stopped(why));
        }
    }

    /// Holds the running scan at its next point, with a `Paused` event: at
    /// the host's request (`None`) or for a fault.
    pub(crate) fn hold_scan(&mut self, why: Option<Fault>) {
        if let Some(run) = &self.scan {
            if why.is_some() {
                self.last_fault = why;
            }
            self.talk.pending_event = Some(run.paused(why));
        }
    }

    pub fn configure_detection(&mut self, s: DetectionSettings) -> Reply<gonio_shared::DetectionReport> {
        if !matches!(self.mode, Mode::Idle | Mode::Faulted) {
            return Err(Fault::Busy);
        }
        self.detector.configure(&mut self.hw, &self.cfg, s)
    }

    /// Learns the detection chain at the current position (laser on).
    pub async fn calibrate(&mut self, req: CalibrateRequest) -> Reply<CalibrationReport> {
        // Refused before the laser goes on (found by the validation property test).
        if let Some(f) = state::transition(self.mode, Event::Measure).refused {
            return Err(f);
        }
        self.detector.check_calibration(req.periods)?;
        self.apply(Event::Measure)?;
        let r = match self.laser(true) {
            Ok(()) => self.detector.calibrate(&mut self.hw, &self.cfg, req.periods).await,
            Err(f) => Err(f),
        };
        self.rest_laser();
        self.finish(r)
    }

    /// Sets the host watch and the idle times; refused (and nothing
    /// changed) for an invalid time.
    pub fn configure_safety(&mut self, c: SafetySettings) -> Reply<()> {
        c.validate()?;
        self.safety = c;
        self.last_heard_us = self.hw.clock.now_us();
        Ok(())
    }

    /// When the host watch fires, if it is on (µs on the head's clock).
    pub(crate) fn silence_deadline(&self) -> Option<u64> {
        self.host_timeout_us().map(|t| self.last_heard_us.saturating_add(t))
    }

    /// The host watch (µs), if it is on.
    pub(crate) fn host_timeout_us(&self) -> Option<u64> {
        let t = units::seconds_to_us(self.safety.host_timeout_s) as u64;
        (t > 0).then_some(t)
    }

    /// When the laser and the drivers let go at rest (µs), for those that
    /// are on and have an idle time.
    fn idle_deadlines(&self) -> [Option<u64>; 2] {
        let after = |on: bool, s: f32| (on && s > 0.0).then(|| self.rest_since_us.saturating_add(units::seconds_to_us(s) as u64));
        [
            after(self.laser_on, self.safety.laser_idle_s),
            after(self.drivers_on, self.safety.idle_drivers_s),
        ]
    }

    /// The next idle deadline at rest.
    pub(crate) fn rest_deadline(&self) -> Option<u64> {
        self.idle_deadlines().into_iter().flatten().min()
    }

    /// At rest, a deadline has passed: the laser and the drivers let go of
    /// what has been idle long enough.
    pub(crate) fn rest_expired(&mut self) {
        let now = self.hw.clock.now_us();
        let [laser, drivers] = self.idle_deadlines().map(|d| d.is_some_and(|d| now >= d));
        if laser {
            let _ = self.apply(Event::LaserIdle);
        }
        if drivers {
            let _ = self.apply(Event::IdleTimeout);
        }
    }

    /// Counts runs of saturated and of dark samples in a scan; a run of
    /// [`SUSPECT_RUN`] stops it.
    pub(crate) fn watch(&mut self, flags: SampleFlags) -> Result<(), Fault> {
        let run = |n: &mut u32, hit: bool| {
            *n = if hit { *n + 1 } else { 0 };
            *n >= SUSPECT_RUN
        };
        if run(&mut self.suspect.saturated, flags.contains(SampleFlags::SATURATED)) {
            return Err(Fault::Saturated);
        }
        if run(&mut self.suspect.dark, flags.contains(SampleFlags::BELOW_NOISE)) {
            return Err(Fault::NoSignal);
        }
        Ok(())
    }

    pub fn load_sanity(&mut self, c: SanityConfig) -> Reply<()> {
        self.sanity = Some(Sanity::new(c)?);
        Ok(())
    }
}
