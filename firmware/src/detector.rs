//! Acquisition of one sample: auto-range the transimpedance gain, discard the
//! periods the amplifier spends settling, integrate, flag.

use crate::board::HeadConfig;
use crate::demod::{demod_period, Accumulator, Reference, MAX_M};
use crate::hw::{AdcStream, Board, ChopTiming, Hardware};
use crate::units;
use embedded_hal::digital::OutputPin;
use gonio_shared::{DetectionReport, DetectionSettings, Fault, SampleFlags};

/// Gain up when the largest code would still sit below this fraction of full
/// scale at ten times the gain; down when codes reach the rails. The band in
/// between is the hysteresis.
const RAISE_BELOW: f32 = 0.7;
/// Amplitudes under this many standard errors are flagged as below noise.
const NOISE_FLOOR_K: f64 = 3.0;

/// A demodulated measurement in SI units, before geometry is attached.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    pub in_phase_v: f32,
    pub quadrature_v: f32,
    pub amplitude_v: f32,
    pub phase_deg: f32,
    pub noise_v: f32,
    pub gain_index: u8,
    pub gain_v_per_a: f32,
    pub periods: u16,
    pub flags: SampleFlags,
}

pub struct Detector {
    settings: DetectionSettings,
    timing: ChopTiming,
    reference: Reference,
    gain: u8,
    /// Calibrated phase delay of the electronics (degrees).
    phase_ref_deg: f32,
    running: bool,
}

impl Detector {
    pub fn new<A: AdcStream>(settings: DetectionSettings) -> Self {
        Self {
            settings,
            timing: units::chop_timing(&settings, A::TIMER_HZ),
            reference: Reference::new(settings.reference, settings.samples_per_period as usize),
            gain: 0,
            phase_ref_deg: 0.0,
            running: false,
        }
    }

    pub fn settings(&self) -> &DetectionSettings {
        &self.settings
    }

    /// Applies validated settings; the ADC restarts on the next measurement.
    pub fn configure<B: Board>(&mut self, hw: &mut Hardware<B>, s: DetectionSettings) -> Result<DetectionReport, Fault> {
        s.validate()?;
        self.settings = s;
        self.timing = units::chop_timing(&s, <B::Adc as AdcStream>::TIMER_HZ);
        self.reference = Reference::new(s.reference, s.samples_per_period as usize);
        self.stop(hw);
        Ok(self.report::<B::Adc>())
    }

    pub fn report<A: AdcStream>(&self) -> DetectionReport {
        let chop = units::chop_hz_actual(self.timing, A::TIMER_HZ);
        let t = self.settings.periods as f32 / chop;
        DetectionReport {
            settings: self.settings,
            chop_hz_actual: chop,
            integration_s: t,
            enbw_hz: 1.0 / (2.0 * t),
        }
    }

    /// Stops the chop and the conversions (laser dark).
    pub fn stop<B: Board>(&mut self, hw: &mut Hardware<B>) {
        hw.adc.stop();
        self.running = false;
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
    async fn period<B: Board>(&mut self, hw: &mut Hardware<B>, buf: &mut [u16], flags: &mut SampleFlags) {
        if hw.adc.next_period(buf).await.is_err() {
            flags.set(SampleFlags::OVERRUN);
        }
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
        let full = ((1u32 << <B::Adc as AdcStream>::BITS) - 1) as u16;
        let n_gains = cfg.detector.gains_v_per_a.len() as u8;
        for _ in 0..2 * n_gains {
            for _ in 0..cfg.detector.settle_periods {
                self.period(hw, buf, flags).await;
            }
            self.period(hw, buf, flags).await;
            let p = demod_period(&self.reference, buf);
            if p.max >= full || p.min == 0 {
                if self.gain == 0 {
                    return Ok(());
                }
                let g = self.gain - 1;
                self.set_gain(hw, g)?;
            } else if (p.max as f32) * 10.0 < RAISE_BELOW * full as f32 && self.gain + 1 < n_gains {
                let g = self.gain + 1;
                self.set_gain(hw, g)?;
            } else {
                return Ok(());
            }
        }
        Ok(())
    }

    /// Takes one sample at the current position.
    pub async fn measure<B: Board>(&mut self, hw: &mut Hardware<B>, cfg: &HeadConfig) -> Result<Measurement, Fault> {
        let mut flags = SampleFlags::default();
        let m = (self.settings.samples_per_period as usize).min(MAX_M);
        let mut buf = [0u16; MAX_M];
        let buf = &mut buf[..m];
        if !self.running {
            self.set_gain(hw, self.gain)?;
            hw.adc.start(self.timing);
            self.running = true;
        }
        if self.settings.auto_range {
            self.auto_range(hw, cfg, buf, &mut flags).await?;
        }
        for _ in 0..cfg.detector.settle_periods {
            self.period(hw, buf, &mut flags).await;
        }
        let mut acc = Accumulator::new();
        for _ in 0..self.settings.periods {
            self.period(hw, buf, &mut flags).await;
            acc.push(demod_period(&self.reference, buf));
        }
        let full = ((1u32 << <B::Adc as AdcStream>::BITS) - 1) as u16;
        if acc.max >= full || acc.min == 0 {
            flags.set(SampleFlags::SATURATED);
        }
        let e = acc.estimate(&self.reference, self.phase_ref_deg as f64);
        if e.amplitude.abs() < NOISE_FLOOR_K * e.std_err {
            flags.set(SampleFlags::BELOW_NOISE);
        }
        let volts = |c: f64| units::codes_to_volts(c as f32, <B::Adc as AdcStream>::BITS, cfg.detector.adc_vref);
        Ok(Measurement {
            in_phase_v: volts(e.i),
            quadrature_v: volts(e.q),
            amplitude_v: volts(e.amplitude),
            phase_deg: e.phase_deg as f32,
            noise_v: volts(e.std_err),
            gain_index: self.gain,
            gain_v_per_a: cfg.detector.gains_v_per_a[self.gain as usize],
            periods: e.periods as u16,
            flags,
        })
    }
}
