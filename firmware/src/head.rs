//! The head: owns the hardware and the state, answers commands, runs scans.
//!
//! Requests are served one at a time in arrival order. A scan is accepted at
//! once and then advanced one point per loop turn; between points the head
//! looks for waiting requests, so status and abort are answered mid-scan.
//! Every change of what the head does goes through the state table
//! ([`crate::state`]) in [`Head::apply`].

use crate::active_scan::ActiveScan;
use crate::config::HeadConfig;
use crate::conversation::Conversation;
use crate::detector::Detector;
use crate::hw::{AdcStream, Board, Clock, Hardware, StepTimer};
use crate::kinematics;
use crate::motion::{self, Position};
use crate::sanity::geometry::FixedGeometry;
use crate::sanity::Sanity;
use crate::state::{self, Drivers, Event, Laser, Mode};
use crate::{homing, units};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::icd::{HomeRequest, MeasureRequest, MoveReport};
use gonio_shared::sample::ScanPosition;
use gonio_shared::{
    Axis, Capabilities, DetectionSettings, Fault, Geometry, HeadState, Identity, LearnReport, LearnRequest, Reply, SafetySettings, Sample,
    SampleFlags, SanityConfig, ScanAccepted, ScanSpec, Signal, Status, VisitChunk, VisitsQueued,
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

pub struct Head<B: Board> {
    pub(crate) cfg: HeadConfig,
    pub(crate) hw: Hardware<B>,
    info: HeadInfo,
    pub(crate) pos: Position,
    pub(crate) detector: Detector,
    sanity: Option<Sanity>,
    pub(crate) scan: Option<ActiveScan>,
    laser_on: bool,
    pub(crate) seq: u32,
    /// What the serve loop keeps of the conversation with the host.
    pub(crate) talk: Conversation,
    pub(crate) samples_flagged: u32,
    samples_remeasured: u32,
    pub(crate) last_fault: Option<Fault>,
    /// Why the laser may not come on until the chip restarts (a crystal
    /// that failed its check at boot, or the `no-laser` image), if it may not.
    laser_inhibited: Option<Fault>,
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
    /// Scan runs started since power-up.
    runs: u32,
}

impl<B: Board> Head<B> {
    /// A head in its safe state; [`Head::prepare`] it once it is in place.
    pub fn new(cfg: HeadConfig, hw: Hardware<B>, info: HeadInfo) -> Self {
        let timer_hz = hw.adc.timer_hz();
        let mut head = Self {
            cfg,
            hw,
            info,
            pos: Position::default(),
            detector: Detector::new(DetectionSettings::default(), timer_hz),
            sanity: None,
            scan: None,
            laser_on: false,
            seq: 0,
            talk: Conversation::default(),
            samples_flagged: 0,
            samples_remeasured: 0,
            last_fault: None,
            laser_inhibited: None,
            mode: Mode::Idle,
            drivers_on: false,
            estop_open: false,
            safety: SafetySettings::default(),
            last_heard_us: 0,
            rest_since_us: 0,
            runs: 0,
        };
        head.safe_state();
        head
    }

    /// Finishes what [`Head::new`] leaves for once the head is in its
    /// place: the detector's regression designs factored (about a million
    /// instructions, once). Apart from `new`: on the chip the head is built
    /// in a frame of its own on its way to a static, and the factors'
    /// temporaries there would sit below the whole head (`chip-bench`'s
    /// `board.stack_bytes_max`). Until then a measurement accumulates its
    /// own Gram matrices: the same estimate, at a higher cost per period.
    pub fn prepare(&mut self) {
        self.detector.factor_designs();
    }

    /// Reports why the head last restarted (its watchdog, or a handler that
    /// made the pins safe and reset the chip), in the status.
    pub fn restarted_by(&mut self, f: Fault) {
        self.last_fault = Some(f);
    }

    /// Keeps the laser off until the chip restarts, for `why` (reported in
    /// the status's `laser_inhibited`, and as the refusal of everything that
    /// needs the laser): the chip layer's answer to a clock it cannot trust,
    /// or the `no-laser` image. The axes still home and move, for bring-up.
    pub fn inhibit_laser(&mut self, why: Fault) {
        self.laser_inhibited = Some(why);
    }

    /// Refuses, before anything moves, what would need an inhibited laser.
    pub(crate) fn laser_permitted(&self) -> Result<(), Fault> {
        self.laser_inhibited.map_or(Ok(()), Err)
    }

    /// Laser off, conversions stopped, drivers disabled, step queues emptied.
    /// Pin errors are ignored here: there is nothing safer left to do.
    pub fn safe_state(&mut self) {
        self.end_sweeping();
        self.hw.steps.clear();
        self.detector.stop(&mut self.hw);
        let _ = self.hw.laser.set_low();
        self.laser_on = false;
        self.drivers(false);
    }

    /// Drops the row a sweep scan is sweeping (its move is braked or cleared
    /// by the caller): the row is swept again on continuing.
    fn end_sweeping(&mut self) {
        if let Some(run) = &mut self.scan {
            run.sweeping = None;
        }
    }

    /// Laser enable low and the chop stopped, at once.
    fn laser_off(&mut self) {
        let _ = self.hw.laser.set_low();
        self.laser_on = false;
        self.detector.stop(&mut self.hw);
    }

    pub(crate) fn drivers(&mut self, on: bool) {
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
    pub(crate) fn finish<T>(&mut self, r: Reply<T>) -> Reply<T> {
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
        self.end_sweeping();
        motion::halt(&mut self.hw, &self.cfg, &mut self.pos).await;
        let _ = self.apply(Event::Stopped);
    }

    pub(crate) fn laser(&mut self, on: bool) -> Result<(), Fault> {
        if on && !self.mode.laser_allowed() {
            return Err(Fault::Busy);
        }
        if on {
            self.laser_permitted()?;
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
        let (run, next_order, total) = self.scan.as_ref().map_or((0, 0, 0), ActiveScan::progress);
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
            laser_inhibited: self.laser_inhibited,
            uptime_us: self.hw.clock.now_us(),
            requests_held: 0,
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
        if let Some(f) = state::transition(self.mode, Event::Measure).refused {
            return Err(f);
        }
        self.laser_permitted()?;
        self.apply(Event::Measure)?;
        let r = self.acquire(req.at, None).await;
        self.rest_laser();
        self.finish(r)
    }

    /// After a measurement at rest: the chop stops, and the laser goes off
    /// unless it is to stay on for its idle time.
    pub(crate) fn rest_laser(&mut self) {
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
        self.laser_permitted()?;
        self.drop_scan(Fault::Aborted);
        self.apply(Event::Scan)?;
        let first_order = spec.first_order;
        self.last_heard_us = self.hw.clock.now_us();
        self.runs = self.runs.wrapping_add(1);
        self.scan = Some(ActiveScan::new(self.runs, spec, total));
        Ok(ScanAccepted {
            points: total,
            first_order,
            run: self.runs,
        })
    }

    /// Queues the next stretch of the running or held scan's visit order.
    /// A chunk that does not start where the queue ends takes nothing, and
    /// what does not fit is left out: the answer says where to go on.
    pub fn queue_visits(&mut self, chunk: &VisitChunk) -> Reply<VisitsQueued> {
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
    pub async fn learn_reference(&mut self, req: LearnRequest) -> Reply<LearnReport> {
        // Refused before the laser goes on (found by the validation property test).
        if let Some(f) = state::transition(self.mode, Event::Measure).refused {
            return Err(f);
        }
        self.detector.check_learning(req.periods)?;
        self.laser_permitted()?;
        self.apply(Event::Measure)?;
        let r = match self.laser(true) {
            Ok(()) => self.detector.learn(&mut self.hw, &self.cfg, req.periods).await,
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

    pub fn load_sanity(&mut self, c: SanityConfig) -> Reply<()> {
        self.sanity = Some(Sanity::new(c)?);
        Ok(())
    }
}
