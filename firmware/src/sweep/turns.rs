//! Running a sweep on the head: a sweep asked for on its own
//! ([`Head::sweep`]), and a sweep scan's row one turn (one sample) at a time
//! between the serve loop's turns ([`Head::sweep_turn`]).

use super::plan as sweep;
use super::sweeping::Sweeping;
use crate::active_scan::ActiveScan;
use crate::head::Head;
use crate::hw::{Board, Clock, StepTimer};
use crate::kinematics;
use crate::motion;
use crate::state::{self, Event};
use crate::units;
use embedded_hal_async::delay::DelayNs;
use gonio_shared::sample::ScanPosition;
use gonio_shared::{AxisAngles, Fault, Reply, SampleFlags, SweepLobe, SweepReport, SweepRequest, SweepRow, SweptSample};

/// What one turn of a sweep scan's row did.
pub(crate) enum SweepTurn {
    /// The sweep began: the stages move, the chop runs.
    Begun,
    /// A sample; more follow.
    Sample(SweptSample),
    /// The row's last sample, and how many it made.
    Last(SweptSample, u32),
}

impl<B: Board> Head<B> {
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
        self.laser_permitted()?;
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
        self.scan.as_ref().is_some_and(|run| run.sweeping.is_some())
    }

    /// Checks what a sweep asks of the detector and of its samples.
    pub(crate) fn check_sweep(&self, periods_per_sample: u16, speed_dps: f32, lobe: Option<&SweepLobe>) -> Reply<()> {
        sweep::check(&self.cfg, periods_per_sample, speed_dps, lobe, self.detector.settings().chop_hz)
    }

    /// One turn of a sweep scan's row at scan position `at`: the first turn
    /// works out and begins the sweep (the arm alone moves, at the row's
    /// speed or its limit), every other one takes one sample; the last ends
    /// the sweep. A row refused (beyond the travel) changes nothing.
    pub(crate) async fn sweep_turn(&mut self, scan: &mut ActiveScan, row: &SweepRow, at: ScanPosition) -> Reply<SweepTurn> {
        let Some(mut sw) = scan.sweeping.take() else {
            self.check_sweep(row.periods_per_sample, row.speed_dps, row.lobe.as_ref())?;
            let p = sweep::row_plan(&self.cfg, row, self.detector.settings().chop_hz)?;
            if !self.pos.all_homed() {
                return Err(Fault::NotHomed);
            }
            scan.sweeping = Some(
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
        // The suspect count of a scan's points, over its samples: a run of
        // saturated ones (8, some 8° of a row at 30 deg/s) ends the scan,
        // and so does a row all of whose samples are below the noise (a
        // dead laser, a blocked beam: a swept sample integrates a third of a
        // point's periods, and a dark floor a few degrees long is no
        // fault); the arm is braked, the sample that completed it not sent.
        sw.lit |= !s.signal.flags.contains(SampleFlags::BELOW_NOISE);
        let counted = scan.count_suspect(s.signal.flags.difference(SampleFlags::BELOW_NOISE));
        let row_dark = !sw.moving && !sw.lit;
        if let Err(f) = counted.and(if row_dark { Err(Fault::NoSignal) } else { Ok(()) }) {
            return Err(self.abandon_sweep(f).await);
        }
        if sw.moving {
            scan.sweeping = Some(sw);
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
}
