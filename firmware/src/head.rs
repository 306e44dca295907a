//! The head: owns the hardware and the state, answers commands, runs scans.
//!
//! Requests are served one at a time in arrival order. A scan is accepted at
//! once and then advanced one point per loop turn; between points the head
//! looks for waiting requests, so status and abort are answered mid-scan.

use crate::board::HeadConfig;
use crate::detector::{Detector, Measurement};
use crate::hw::{Board, Clock, Hardware, StepTimer};
use crate::kinematics;
use crate::motion::plan::Planner;
use crate::motion::{self, Position};
use crate::sanity::Sanity;
use crate::{homing, units};
use embedded_hal::digital::OutputPin;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::icd::{HomeRequest, MeasureRequest, MoveReport};
use gonio_shared::sample::ScanPosition;
use gonio_shared::{
    Axis, CalibrateRequest, CalibrationReport, Capabilities, DetectionSettings, Fault, Geometry, HeadState, Identity, Reply,
    SafetySettings, Sample, SampleFlags, SanityConfig, ScanAccepted, ScanEvent, ScanSpec, Status,
};
use postcard_rpc::header::VarKeyKind;

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

/// Runs of suspicious samples in the current scan.
#[derive(Debug, Default, Clone, Copy)]
struct SuspectRuns {
    saturated: u32,
    dark: u32,
}

pub(crate) struct ScanRun {
    /// Number of the run since power-up (`ScanAccepted::run`).
    pub(crate) run: u32,
    pub(crate) spec: ScanSpec,
    pub(crate) planner: Planner,
    pub(crate) total: u32,
    pub(crate) next_order: u32,
    pub(crate) measured: u32,
    pub(crate) skipped: u32,
}

pub struct Head<B: Board> {
    pub(crate) cfg: HeadConfig,
    hw: Hardware<B>,
    info: HeadInfo,
    pos: Position,
    detector: Detector,
    sanity: Option<Sanity>,
    pub(crate) scan: Option<ScanRun>,
    /// A scan event to publish after the current reply (an abort's `Stopped`).
    pub(crate) pending_event: Option<ScanEvent>,
    laser_on: bool,
    seq: u32,
    pub(crate) topic_seq: u32,
    /// Key width the host uses; replies and topics follow it.
    pub(crate) key_kind: VarKeyKind,
    samples_flagged: u32,
    samples_remeasured: u32,
    pub(crate) last_fault: Option<Fault>,
    /// Longest host silence during a scan (µs), 0 for no watch.
    host_timeout_us: u64,
    /// When the host was last heard (µs, the head's clock).
    last_heard_us: u64,
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
            pending_event: None,
            laser_on: false,
            seq: 0,
            topic_seq: 0,
            key_kind: VarKeyKind::Key8,
            samples_flagged: 0,
            samples_remeasured: 0,
            last_fault: None,
            host_timeout_us: 0,
            last_heard_us: 0,
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
        self.hw.steps.clear();
        self.detector.stop(&mut self.hw);
        let _ = self.hw.laser.set_low();
        self.laser_on = false;
        for en in self.hw.enable_n.iter_mut() {
            let _ = en.set_high();
        }
    }

    fn laser(&mut self, on: bool) -> Result<(), Fault> {
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
        Status {
            state: match &self.scan {
                Some(s) => HeadState::Scanning {
                    next_order: s.next_order,
                    total: s.total,
                },
                None => HeadState::Idle,
            },
            homed: self.pos.all_homed(),
            laser_on: self.laser_on,
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

    fn note<T>(&mut self, r: Reply<T>) -> Reply<T> {
        if let Err(f) = &r {
            self.last_fault = Some(*f);
        }
        r
    }

    pub async fn home(&mut self, req: HomeRequest) -> Reply<gonio_shared::AxisAngles> {
        if self.scan.is_some() {
            return Err(Fault::Busy);
        }
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
        self.note(r)
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
        if self.scan.is_some() {
            return Err(Fault::Busy);
        }
        let r = self.goto(&g).await;
        self.note(r)
    }

    /// Moves (if asked), settles, and takes one sample with the laser on.
    pub(crate) async fn acquire(&mut self, at: Option<Geometry>, scan: Option<ScanPosition>) -> Reply<Sample> {
        let target = match at {
            Some(g) => {
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
            m.flags.set(SampleFlags::REMEASURED);
            self.samples_remeasured = self.samples_remeasured.wrapping_add(1);
        }
        let mut flags = m.flags;
        if splitter {
            flags.set(SampleFlags::THROUGH_SPLITTER);
        }
        if flags.0 & !SampleFlags::THROUGH_SPLITTER != 0 {
            self.samples_flagged = self.samples_flagged.wrapping_add(1);
        }
        let s = Sample {
            seq: self.seq,
            scan,
            timestamp_us: self.hw.clock.now_us(),
            target,
            reached,
            axes,
            in_phase_v: m.in_phase_v,
            quadrature_v: m.quadrature_v,
            amplitude_v: m.amplitude_v,
            magnitude_v: m.magnitude_v,
            phase_deg: m.phase_deg,
            noise_v: m.noise_v,
            gain_v_per_a: m.gain_v_per_a,
            gain_index: m.gain_index,
            periods: m.periods,
            flags,
        };
        self.seq = self.seq.wrapping_add(1);
        Ok(s)
    }

    /// One detector reading, checked against the loaded model.
    async fn measure_checked(&mut self, at: &Geometry, through_splitter: bool) -> Reply<Measurement> {
        let mut m = match self.detector.measure(&mut self.hw, &self.cfg).await {
            Ok(m) => m,
            Err(f) => {
                self.safe_state();
                return Err(f);
            }
        };
        if let Some(s) = &self.sanity {
            let expected = s.expected_v(at, m.gain_v_per_a, through_splitter);
            if expected.is_none_or(|e| s.mismatch(e, m.amplitude_v, m.noise_v)) {
                m.flags.set(SampleFlags::MODEL_MISMATCH);
            }
        }
        Ok(m)
    }

    pub async fn measure(&mut self, req: MeasureRequest) -> Reply<Sample> {
        if self.scan.is_some() {
            return Err(Fault::Busy);
        }
        let r = self.acquire(req.at, None).await;
        self.detector.stop(&mut self.hw);
        let _ = self.laser(false);
        self.note(r)
    }

    pub fn start_scan(&mut self, spec: ScanSpec) -> Reply<ScanAccepted> {
        if self.scan.is_some() {
            return Err(Fault::Busy);
        }
        let total = spec.validate()?;
        if !self.pos.all_homed() {
            return Err(Fault::NotHomed);
        }
        let first_order = spec.first_order;
        // The plan always starts from the park position, wherever the stages
        // are, so that the host and a resumed scan replay the same order.
        let mut planner = Planner::new(&spec, motion::PARK);
        while planner.order() < first_order && planner.next(&self.cfg, &spec).is_some() {}
        self.suspect = SuspectRuns::default();
        self.last_heard_us = self.hw.clock.now_us();
        self.runs = self.runs.wrapping_add(1);
        self.scan = Some(ScanRun {
            run: self.runs,
            spec,
            planner,
            total,
            next_order: first_order,
            measured: 0,
            skipped: 0,
        });
        Ok(ScanAccepted {
            points: total,
            first_order,
            run: self.runs,
        })
    }

    pub fn abort(&mut self) -> Status {
        if let Some(run) = self.scan.take() {
            self.last_fault = Some(Fault::Aborted);
            self.pending_event = Some(ScanEvent::Stopped {
                run: run.run,
                next_order: run.next_order,
                reason: Fault::Aborted,
            });
        }
        self.safe_state();
        self.status()
    }

    pub fn configure_detection(&mut self, s: DetectionSettings) -> Reply<gonio_shared::DetectionReport> {
        if self.scan.is_some() {
            return Err(Fault::Busy);
        }
        self.detector.configure(&mut self.hw, s)
    }

    /// Learns the detection chain at the current position (laser on).
    pub async fn calibrate(&mut self, req: CalibrateRequest) -> Reply<CalibrationReport> {
        if self.scan.is_some() {
            return Err(Fault::Busy);
        }
        // Refused before the laser goes on (found by the validation property test).
        self.detector.check_calibration(req.periods)?;
        let r = match self.laser(true) {
            Ok(()) => self.detector.calibrate(&mut self.hw, &self.cfg, req.periods).await,
            Err(f) => Err(f),
        };
        self.detector.stop(&mut self.hw);
        let _ = self.laser(false);
        self.note(r)
    }

    /// Sets the host watch; refused (and nothing changed) for an invalid timeout.
    pub fn configure_safety(&mut self, c: SafetySettings) -> Reply<()> {
        c.validate()?;
        self.host_timeout_us = units::seconds_to_us(c.host_timeout_s) as u64;
        self.last_heard_us = self.hw.clock.now_us();
        Ok(())
    }

    /// Notes that a frame came from the host.
    pub(crate) fn heard_host(&mut self) {
        self.last_heard_us = self.hw.clock.now_us();
    }

    /// The run and position of a running scan, if the host has been silent
    /// longer than its timeout.
    pub(crate) fn host_silent(&self) -> Option<(u32, u32)> {
        let run = self.scan.as_ref()?;
        let silent = self.hw.clock.now_us().saturating_sub(self.last_heard_us);
        (self.host_timeout_us > 0 && silent > self.host_timeout_us).then_some((run.run, run.next_order))
    }

    /// Counts runs of saturated and of dark samples in a scan; a run of
    /// [`SUSPECT_RUN`] stops it.
    pub(crate) fn watch(&mut self, s: &Sample) -> Result<(), Fault> {
        let run = |n: &mut u32, hit: bool| {
            *n = if hit { *n + 1 } else { 0 };
            *n >= SUSPECT_RUN
        };
        if run(&mut self.suspect.saturated, s.flags.contains(SampleFlags::SATURATED)) {
            return Err(Fault::Saturated);
        }
        if run(&mut self.suspect.dark, s.flags.contains(SampleFlags::BELOW_NOISE)) {
            return Err(Fault::NoSignal);
        }
        Ok(())
    }

    pub fn load_sanity(&mut self, c: SanityConfig) -> Reply<()> {
        self.sanity = Some(Sanity::new(c)?);
        Ok(())
    }
}
