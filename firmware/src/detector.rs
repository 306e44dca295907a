//! Acquisition of one sample: auto-range the transimpedance gain, discard the
//! periods the amplifier spends settling, integrate, flag. Also the
//! learning of the electronics' phase and the matched waveform.

use crate::config::HeadConfig;
use crate::demod::{Design, Estimate, Integrator, Learned, Learner, Reference, MAX_M};
use crate::hw::{AdcStream, Board, ChopTiming, Clock, Hardware, StepTimer};
use crate::units;
use core::future::{poll_fn, Future};
use core::pin::pin;
use core::task::Poll;
use embedded_hal::digital::OutputPin;
use gonio_shared::{DetectionReport, DetectionSettings, Fault, Field, LearnReport, Reference as Kind, SampleFlags, Signal, SweepRequest};

/// Gain up when the largest code would still sit below this fraction of full
/// scale at ten times the gain; down when codes reach the rails. The band in
/// between is the hysteresis.
const RAISE_BELOW: f32 = 0.7;
/// Amplitudes under this many standard errors are flagged as below noise.
const NOISE_FLOOR_K: f64 = 3.0;
/// A learned phase is checked on samples at least this far above noise...
const PHASE_CHECK_SNR: f64 = 10.0;
/// ...and flagged when it is further than this from the learned phase.
const PHASE_TOLERANCE_DEG: f64 = 20.0;
/// Learning needs at least this signal-to-noise ratio and period count.
const LEARNING_SNR: f64 = 30.0;
const LEARNING_MIN_PERIODS: u16 = 8;

pub struct Detector {
    settings: DetectionSettings,
    timing: ChopTiming,
    chop_hz: f64,
    reference: Reference,
    /// The regression's design for `settings.periods` at `chop_hz`.
    design: Design,
    /// The design of a sweep's samples ([`Detector::design_sweep`]), kept
    /// here rather than in the sweep's state, which the serve loop's future
    /// would otherwise carry (3 KiB) through every await of a scan.
    swept: Design,
    /// What was learned and the chop timing it was learned at.
    learned: Option<(Learned, ChopTiming)>,
    gain: u8,
    /// The gain changed during a sweep: the next swept sample first
    /// discards the periods the amplifier needs.
    resettle: bool,
    running: bool,
}

impl Detector {
    /// Starts with `settings`; a matched reference there falls back to the
    /// square until the waveform has been learned. The designs are factored
    /// by [`Detector::factor_designs`] once the head is in its place
    /// ([`crate::Head::prepare`]).
    pub fn new(settings: DetectionSettings, timer_hz: u32) -> Self {
        let timing = units::chop_timing(&settings, timer_hz);
        let chop_hz = units::chop_hz_actual(timing, timer_hz) as f64;
        Self {
            settings,
            timing,
            chop_hz,
            reference: Reference::new(settings.reference, settings.samples_per_period as usize, None),
            design: Design::unfactored(settings.periods as u32, chop_hz),
            swept: Design::unfactored(SweepRequest::PERIODS_MAX as u32, chop_hz),
            learned: None,
            gain: 0,
            resettle: false,
            running: false,
        }
    }

    /// Factors the designs [`Detector::new`] left unfactored (a no-op once
    /// done).
    pub fn factor_designs(&mut self) {
        self.design.precompute();
        self.swept.precompute();
    }

    pub fn settings(&self) -> &DetectionSettings {
        &self.settings
    }

    fn learned(&self) -> Option<&Learned> {
        self.learned.as_ref().filter(|(_, t)| *t == self.timing).map(|(l, _)| l)
    }

    /// Applies validated settings; the ADC restarts on the next measurement.
    /// A matched reference needs one learned at the same chop timing.
    pub fn configure<B: Board>(&mut self, hw: &mut Hardware<B>, cfg: &HeadConfig, s: DetectionSettings) -> Result<DetectionReport, Fault> {
        s.validate()?;
        let timer_hz = hw.adc.timer_hz();
        let timing = units::chop_timing(&s, timer_hz);
        let learned = self.learned.as_ref().is_some_and(|(_, t)| *t == timing);
        if s.reference == Kind::Matched && !learned {
            return Err(Fault::NotLearned);
        }
        self.settings = s;
        self.timing = timing;
        self.chop_hz = units::chop_hz_actual(timing, timer_hz) as f64;
        self.reference = Reference::new(s.reference, s.samples_per_period as usize, self.learned());
        self.design = Design::new(s.periods as u32, self.chop_hz);
        self.stop(hw);
        Ok(self.report(cfg))
    }

    pub fn report(&self, cfg: &HeadConfig) -> DetectionReport {
        let chop = self.chop_hz as f32;
        let t = self.settings.periods as f32 / chop;
        DetectionReport {
            settings: self.settings,
            chop_hz_actual: chop,
            integration_s: t,
            enbw_hz: 1.0 / (2.0 * t),
            settle_periods: cfg.detector.settle_periods,
        }
    }

    /// Stops the chop and the conversions (laser dark).
    pub fn stop<B: Board>(&mut self, hw: &mut Hardware<B>) {
        hw.adc.stop();
        self.running = false;
        self.resettle = false;
    }

    fn set_gain<B: Board>(&mut self, hw: &mut Hardware<B>, g: u8) -> Result<(), Fault> {
        self.gain = g.min(3);
        let bits = [self.gain & 1 != 0, self.gain & 2 != 0];
        for (pin, on) in hw.gain.iter_mut().zip(bits) {
            let r = if on { pin.set_high() } else { pin.set_low() };
            r.map_err(|_| Fault::Gpio)?;
        }
        Ok(())
    }

    /// Reads one period into `buf`, noting an overrun in `flags`.
    async fn period<B: Board>(hw: &mut Hardware<B>, buf: &mut [u16], flags: &mut SampleFlags) {
        if hw.adc.next_period(buf).await.is_err() {
            flags.insert(SampleFlags::OVERRUN);
        }
    }

    /// Discards the periods the amplifier needs after a gain change.
    async fn settle<B: Board>(hw: &mut Hardware<B>, cfg: &HeadConfig, buf: &mut [u16], flags: &mut SampleFlags) {
        for _ in 0..cfg.detector.settle_periods {
            Self::period(hw, buf, flags).await;
        }
    }

    fn full_scale<B: Board>() -> u16 {
        ((1u32 << <B::Adc as AdcStream>::BITS) - 1) as u16
    }

    /// Chooses the gain: discard the settling periods after each change, look
    /// at one period, step down on saturation, up when there is headroom.
    async fn auto_range<B: Board>(
        &mut self,
        hw: &mut Hardware<B>,
        cfg: &HeadConfig,
        buf: &mut [u16],
        flags: &mut SampleFlags,
    ) -> Result<(), Fault> {
        let n_gains = cfg.detector.gains_v_per_a.len() as u8;
        for _ in 0..2 * n_gains {
            Self::settle(hw, cfg, buf, flags).await;
            Self::period(hw, buf, flags).await;
            let (min, max) = buf.iter().fold((u16::MAX, 0), |(lo, hi), &c| (lo.min(c), hi.max(c)));
            match self.next_gain::<B>(cfg, min, max) {
                Some(g) => self.set_gain(hw, g)?,
                None => return Ok(()),
            }
        }
        Ok(())
    }

    /// The gain one step from the current one that codes from `min` to
    /// `max` ask for: lower when they reach the rails, higher when ten times
    /// them would stay below [`RAISE_BELOW`] of full scale; `None` when the
    /// gain is right or at its end.
    fn next_gain<B: Board>(&self, cfg: &HeadConfig, min: u16, max: u16) -> Option<u8> {
        let full = Self::full_scale::<B>();
        let n_gains = cfg.detector.gains_v_per_a.len() as u8;
        if max >= full || min == 0 {
            self.gain.checked_sub(1)
        } else if (max as f32) * 10.0 < RAISE_BELOW * full as f32 && self.gain + 1 < n_gains {
            Some(self.gain + 1)
        } else {
            None
        }
    }

    /// Starts the chop if needed, ranges the gain and lets the amplifier settle.
    async fn prepare<B: Board>(
        &mut self,
        hw: &mut Hardware<B>,
        cfg: &HeadConfig,
        buf: &mut [u16],
        flags: &mut SampleFlags,
    ) -> Result<(), Fault> {
        if !self.running {
            self.set_gain(hw, self.gain)?;
            hw.adc.start(self.timing);
            self.running = true;
        }
        if self.settings.auto_range {
            self.auto_range(hw, cfg, buf, flags).await?;
        }
        Self::settle(hw, cfg, buf, flags).await;
        Ok(())
    }

    fn samples_per_period(&self) -> usize {
        (self.settings.samples_per_period as usize).min(MAX_M)
    }

    /// Takes one sample at the current position.
    pub async fn measure<B: Board>(&mut self, hw: &mut Hardware<B>, cfg: &HeadConfig) -> Result<Signal, Fault> {
        let mut flags = SampleFlags::default();
        let mut buf = [0u16; MAX_M];
        let buf = &mut buf[..self.samples_per_period()];
        self.prepare(hw, cfg, buf, &mut flags).await?;
        let it = self.accumulate(hw, buf, &mut flags, &self.design, None).await;
        Ok(self.conclude::<B>(cfg, &it, flags).await.0)
    }

    /// Computes the regression's design of a sweep's samples (`periods`
    /// each), once for all of them, before the chop starts.
    pub fn design_sweep(&mut self, periods: u16) {
        self.swept = Design::new(periods as u32, self.chop_hz);
    }

    /// Starts the chop, ranges the gain and lets the amplifier settle for a
    /// sweep, at its start. A block lost meanwhile is a fault: the ring
    /// would be out of step with the chop for the whole sweep.
    pub async fn prepare_sweep<B: Board>(&mut self, hw: &mut Hardware<B>, cfg: &HeadConfig) -> Result<(), Fault> {
        let mut flags = SampleFlags::default();
        let mut buf = [0u16; MAX_M];
        let buf = &mut buf[..self.samples_per_period()];
        self.prepare(hw, cfg, buf, &mut flags).await?;
        if flags.contains(SampleFlags::OVERRUN) {
            return Err(Fault::AdcOverrun);
        }
        Ok(())
    }

    /// Takes one swept sample while the step timer runs a move: the chop
    /// runs on from the previous one (no ranging, no settling), the periods
    /// of the sweep's design ([`Detector::design_sweep`]) are integrated. Returns its signal, and the steps the timer
    /// had emitted and the time when its last period's codes arrived, read
    /// before the estimate (the conversions go on meanwhile: the next
    /// sample's first period begins there). `moving` turns false once the
    /// move is over.
    ///
    /// A sweep ranges as it goes (with `auto_range` set): a sample whose
    /// codes reached the rails, or that would fit ten times over, steps the
    /// gain for the next one
    /// ([`Detector::next_gain`]), which first discards the periods the
    /// amplifier needs ([`Detector::resettle_moving`]). A lobe's peak
    /// crossed at a gain set where the row began saturates one or two
    /// samples, not the whole peak.
    pub async fn measure_moving<B: Board>(
        &mut self,
        hw: &mut Hardware<B>,
        cfg: &HeadConfig,
        moving: &mut bool,
    ) -> Result<(Signal, [u32; 3], u64), Fault> {
        let mut flags = SampleFlags::default();
        let mut buf = [0u16; MAX_M];
        let buf = &mut buf[..self.samples_per_period()];
        let it = self.accumulate(hw, buf, &mut flags, &self.swept, Some(moving)).await;
        let (emitted, at_us) = (hw.steps.emitted(), hw.clock.now_us());
        let (signal, (min, max)) = self.conclude::<B>(cfg, &it, flags).await;
        if let Some(g) = self.next_gain::<B>(cfg, min, max).filter(|_| self.settings.auto_range) {
            self.set_gain(hw, g)?;
            self.resettle = true;
        }
        Ok((signal, emitted, at_us))
    }

    /// Discards the periods the amplifier needs after a sweep's gain
    /// changed, if it did: the steps the timer had emitted and the time
    /// when they are over, where the next sample begins. A block lost
    /// meanwhile is a fault, as within a sample: the ring would be out of
    /// step with the chop for the rest of the sweep.
    pub async fn resettle_moving<B: Board>(
        &mut self,
        hw: &mut Hardware<B>,
        cfg: &HeadConfig,
        moving: &mut bool,
    ) -> Result<Option<([u32; 3], u64)>, Fault> {
        if !core::mem::take(&mut self.resettle) {
            return Ok(None);
        }
        let mut flags = SampleFlags::default();
        let mut buf = [0u16; MAX_M];
        let buf = &mut buf[..self.samples_per_period()];
        for _ in 0..cfg.detector.settle_periods {
            period_moving(hw, buf, &mut flags, moving).await;
        }
        if flags.contains(SampleFlags::OVERRUN) {
            return Err(Fault::AdcOverrun);
        }
        Ok(Some((hw.steps.emitted(), hw.clock.now_us())))
    }

    /// Integrates `design`'s periods (while a move runs, when `moving` is
    /// given).
    async fn accumulate<'r, B: Board>(
        &'r self,
        hw: &mut Hardware<B>,
        buf: &mut [u16],
        flags: &mut SampleFlags,
        design: &Design,
        mut moving: Option<&mut bool>,
    ) -> Integrator<'r> {
        let mut it = Integrator::with(&self.reference, design.clone());
        for _ in 0..design.planned() {
            match moving.as_deref_mut() {
                Some(m) => period_moving(hw, buf, flags, m).await,
                None => Self::period(hw, buf, flags).await,
            }
            it.push(buf);
        }
        it
    }

    /// The estimate of an integration, flagged, as a signal, and the
    /// lowest and highest codes it saw. The integration by reference: moved
    /// in, it would be held twice across the await (as the argument and as
    /// the local the body moves it to), 5 KiB more in every future that
    /// awaits a measurement.
    async fn conclude<B: Board>(&self, cfg: &HeadConfig, it: &Integrator<'_>, mut flags: SampleFlags) -> (Signal, (u16, u16)) {
        // The two fits of the estimate are the longest computations of a
        // measurement on the chip: the executor runs between them.
        let drift = it.drift();
        embassy_futures::yield_now().await;
        let e = it.estimate_with(drift);
        self.flag(&e, Self::full_scale::<B>(), &mut flags);
        (self.signal::<B>(cfg, &e, flags), (e.min, e.max))
    }

    fn flag(&self, e: &Estimate, full: u16, flags: &mut SampleFlags) {
        if e.max >= full || e.min == 0 {
            flags.insert(SampleFlags::SATURATED);
        }
        if e.amplitude.abs() < NOISE_FLOOR_K * e.std_err {
            flags.insert(SampleFlags::BELOW_NOISE);
        }
        if let Some(l) = self.learned() {
            let snr = e.magnitude / e.std_err.max(1e-12);
            let off = units::wrap_deg(e.phase_deg - l.phase_square.to_degrees());
            let reference_off = match self.reference.kind() {
                Kind::Sine => units::wrap_deg(e.phase_deg - l.phase_sine.to_degrees()),
                Kind::Square | Kind::Matched => off,
            };
            if snr > PHASE_CHECK_SNR && libm::fabs(reference_off) > PHASE_TOLERANCE_DEG {
                flags.insert(SampleFlags::PHASE_OFF);
            }
        }
    }

    fn signal<B: Board>(&self, cfg: &HeadConfig, e: &Estimate, flags: SampleFlags) -> Signal {
        let volts = |c: f64| units::codes_to_volts(c as f32, <B::Adc as AdcStream>::BITS, cfg.detector.adc_vref);
        Signal {
            in_phase_v: volts(e.i),
            quadrature_v: volts(e.q),
            amplitude_v: volts(e.amplitude),
            magnitude_v: volts(e.magnitude),
            phase_deg: e.phase_deg as f32,
            noise_v: volts(e.std_err),
            gain_index: self.gain,
            gain_v_per_a: cfg.detector.gains_v_per_a[self.gain as usize],
            periods: e.periods as u16,
            flags,
        }
    }

    /// Refuses a learning length out of range; called before the laser
    /// is switched on for it.
    pub fn check_learning(&self, periods: u16) -> Result<(), Fault> {
        let chop_s = 1.0 / self.chop_hz as f32;
        if periods < LEARNING_MIN_PERIODS || periods as f32 * chop_s > DetectionSettings::INTEGRATION_MAX_S * 6.0 {
            return Err(Fault::InvalidValue(Field::Periods));
        }
        Ok(())
    }

    /// Learns the phase of the electronics and the matched waveform on the
    /// signal at the current position, which must be strong and steady.
    pub async fn learn<B: Board>(&mut self, hw: &mut Hardware<B>, cfg: &HeadConfig, periods: u16) -> Result<LearnReport, Fault> {
        self.check_learning(periods)?;
        let m = self.samples_per_period();
        let mut flags = SampleFlags::default();
        let mut buf = [0u16; MAX_M];
        let buf = &mut buf[..m];
        self.prepare(hw, cfg, buf, &mut flags).await?;
        let square = Reference::new(Kind::Square, m, None);
        let mut it = Integrator::new(&square, periods as u32, self.chop_hz);
        let mut learner = Learner::new(m, periods as u32, self.chop_hz);
        for _ in 0..periods {
            Self::period(hw, buf, &mut flags).await;
            it.push(buf);
            learner.push(buf);
        }
        let e = it.estimate();
        if e.max >= Self::full_scale::<B>() || e.min == 0 {
            return Err(Fault::Saturated);
        }
        let snr = e.magnitude / e.std_err.max(1e-12);
        if flags.contains(SampleFlags::OVERRUN) || snr < LEARNING_SNR {
            return Err(Fault::WeakSignal);
        }
        let learned = learner.finish().ok_or(Fault::WeakSignal)?;
        self.learned = Some((learned, self.timing));
        self.reference = Reference::new(self.settings.reference, m, self.learned());
        let phase = self.learned().map_or(0.0, |l| match self.settings.reference {
            Kind::Sine => l.phase_sine,
            Kind::Square | Kind::Matched => l.phase_square,
        });
        let volts = units::codes_to_volts(e.magnitude as f32, <B::Adc as AdcStream>::BITS, cfg.detector.adc_vref);
        Ok(LearnReport {
            phase_deg: phase.to_degrees() as f32,
            amplitude_v: volts,
            gain_index: self.gain,
            snr: snr as f32,
            periods,
        })
    }
}

/// Reads one chop period into `buf` while the step timer runs a move, and
/// polls the move meanwhile (the simulated head's steps run only when
/// polled; the chip's interrupt needs nothing): `moving` turns false once
/// the move is over. The conversions are polled first, so in the simulated
/// head they run the time and the steps catch up with it.
async fn period_moving<B: Board>(hw: &mut Hardware<B>, buf: &mut [u16], flags: &mut SampleFlags, moving: &mut bool) {
    let Hardware { adc, steps, .. } = hw;
    let mut period = pin!(adc.next_period(buf));
    let mut done = pin!(steps.finished());
    let r = poll_fn(|cx| {
        if let Poll::Ready(r) = period.as_mut().poll(cx) {
            return Poll::Ready(r);
        }
        if *moving && done.as_mut().poll(cx).is_ready() {
            *moving = false;
        }
        Poll::Pending
    })
    .await;
    if r.is_err() {
        flags.insert(SampleFlags::OVERRUN);
    }
}
