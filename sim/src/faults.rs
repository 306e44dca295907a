//! Faults the simulated head can be made to suffer (the fault
//! matrix of docs/faults.md, `gonio scan --sim --inject`): on its link to the host, and in its
//! hardware. The schedule is shared (`Arc`) between the host and every head
//! built from the same `SimConfig`, so a one-off fault fires once even when
//! the host reconnects to a fresh head, and a test can clear a lasting fault
//! (the operator's repair) before resuming.

use anyhow::{bail, Context, Result};
use std::sync::{Arc, Mutex, MutexGuard};

/// A fault of the link, hitting the `at`-th frame the head sends or (a
/// request fault) receives, from 1, counted over the whole schedule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkFault {
    /// The frame is lost.
    Drop,
    /// One byte of the frame is flipped.
    Corrupt,
    /// The frame arrives twice.
    Duplicate,
    /// The frame arrives after the next one.
    Reorder,
    /// The frame arrives this many milliseconds late (the head waits).
    Delay(u32),
    /// The cable is pulled: the link closes both ways.
    Disconnect,
}

/// A fault of the head's hardware. Moves are counted with the laser on, so
/// the N-th move is the one to the N+1-th point the laser sees (a scan's
/// points, a monitor's readings).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HardwareFault {
    /// The home switch of an axis never closes (broken wire).
    SwitchStuckOpen(usize),
    /// The home switch of an axis is always closed (stuck lever).
    SwitchStuckClosed(usize),
    /// From the `at`-th move on, the ADC reads full scale (stray light, a
    /// failed amplifier).
    AdcSaturated,
    /// From the `at`-th move on, the laser emits nothing.
    LaserDead,
    /// The `at`-th move never ends (a stalled step timer or driver).
    Stall,
    /// After the `at`-th move, this many ADC blocks are lost (DMA overrun).
    DmaOverrun(u32),
    /// From power-up, the crystal runs at this frequency (kHz; 0: it never
    /// starts) instead of the board's: the head comes up on its internal
    /// oscillator with the laser inhibited, as the chip does.
    Crystal(u32),
}

/// Which way a faulty frame travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// From the head: replies and scan events.
    ToHost,
    /// From the host: requests.
    ToHead,
}

#[derive(Debug, Default)]
pub struct FaultSchedule {
    /// Link faults by direction and frame number, not yet fired.
    pub link: Vec<(Direction, u64, LinkFault)>,
    /// Hardware faults by lit move number (switch faults: from the start).
    pub hardware: Vec<(u64, HardwareFault)>,
    /// Frames the heads of this schedule have sent.
    pub frames_sent: u64,
    /// Frames the heads of this schedule have received.
    pub frames_received: u64,
}

/// The shared schedule.
#[derive(Debug, Clone, Default)]
pub struct Faults(Arc<Mutex<FaultSchedule>>);

impl Faults {
    /// The schedule, held while the guard lives (a poisoned lock still
    /// gives it: the faults are plain data).
    pub fn lock(&self) -> MutexGuard<'_, FaultSchedule> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Removes every hardware fault: the repair before a resume.
    pub fn repair(&self) {
        self.lock().hardware.clear();
    }

    /// Counts a frame travelling `way`; returns the link fault that hits it.
    pub fn next_frame(&self, way: Direction) -> Option<LinkFault> {
        let mut p = self.lock();
        let count = match way {
            Direction::ToHost => &mut p.frames_sent,
            Direction::ToHead => &mut p.frames_received,
        };
        *count += 1;
        let n = *count;
        let i = p.link.iter().position(|(w, at, _)| *w == way && *at == n)?;
        Some(p.link.remove(i).2)
    }

    /// The crystal's frequency (kHz) when it is not the board's.
    pub fn crystal_khz(&self) -> Option<u32> {
        self.lock().hardware.iter().find_map(|(_, h)| match h {
            HardwareFault::Crystal(khz) => Some(*khz),
            _ => None,
        })
    }

    /// Whether a hardware fault is active after `moves` moves.
    pub fn active(&self, moves: u64, f: impl Fn(&HardwareFault) -> bool) -> bool {
        self.lock().hardware.iter().any(|(at, h)| moves >= *at && f(h))
    }

    /// Takes one lost ADC block, if a DMA overrun is due after `moves` moves.
    pub fn take_overrun(&self, moves: u64) -> bool {
        let mut p = self.lock();
        let Some(i) = p
            .hardware
            .iter()
            .position(|(at, h)| moves >= *at && matches!(h, HardwareFault::DmaOverrun(n) if *n > 0))
        else {
            return false;
        };
        if let (_, HardwareFault::DmaOverrun(n)) = &mut p.hardware[i] {
            *n -= 1;
        }
        true
    }

    /// Fires a stall due by move `moves`, once.
    pub fn take_stall(&self, moves: u64) -> bool {
        let mut p = self.lock();
        match p.hardware.iter().position(|(at, h)| *at <= moves && *h == HardwareFault::Stall) {
            Some(i) => {
                p.hardware.remove(i);
                true
            }
            None => false,
        }
    }

    /// Parses `KIND@N[:ARG],...`: link faults `drop, corrupt, duplicate,
    /// reorder, delay (ARG ms), disconnect` at the N-th frame the head sends,
    /// the same with a `req-` prefix at the N-th request it receives (status
    /// traffic not counted, see `faulty_link`); hardware faults `switch-open,
    /// switch-closed` (ARG axis 0–2, N ignored), `saturated, laser-dead,
    /// stall, overrun (ARG blocks)` at move N.
    pub fn parse(spec: &str) -> Result<Faults> {
        let faults = Faults::default();
        {
            let mut p = faults.lock();
            for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                let (kind, rest) = item.split_once('@').with_context(|| format!("fault `{item}` is not KIND@N"))?;
                let (n, arg) = match rest.split_once(':') {
                    Some((n, a)) => (n, Some(a)),
                    None => (rest, None),
                };
                let n: u64 = n.parse().with_context(|| format!("fault `{item}`: `{n}` is not a count"))?;
                let arg = |default: u32| -> Result<u32> {
                    arg.map_or(Ok(default), |a| {
                        a.parse().with_context(|| format!("fault `{item}`: `{a}` is not a number"))
                    })
                };
                let axis = || -> Result<usize> {
                    let a = arg(0)? as usize;
                    if a > 2 {
                        bail!("fault `{item}`: axis {a} is not 0, 1 or 2");
                    }
                    Ok(a)
                };
                let (way, link_kind) = match kind.strip_prefix("req-") {
                    Some(k) => (Direction::ToHead, k),
                    None => (Direction::ToHost, kind),
                };
                let link = match link_kind {
                    "drop" => Some(LinkFault::Drop),
                    "corrupt" => Some(LinkFault::Corrupt),
                    "duplicate" => Some(LinkFault::Duplicate),
                    "reorder" => Some(LinkFault::Reorder),
                    "delay" => Some(LinkFault::Delay(arg(100)?)),
                    "disconnect" => Some(LinkFault::Disconnect),
                    _ => None,
                };
                if let Some(f) = link {
                    p.link.push((way, n, f));
                    continue;
                }
                match kind {
                    "switch-open" => p.hardware.push((0, HardwareFault::SwitchStuckOpen(axis()?))),
                    "switch-closed" => p.hardware.push((0, HardwareFault::SwitchStuckClosed(axis()?))),
                    "saturated" => p.hardware.push((n, HardwareFault::AdcSaturated)),
                    "laser-dead" => p.hardware.push((n, HardwareFault::LaserDead)),
                    "stall" => p.hardware.push((n, HardwareFault::Stall)),
                    "overrun" => p.hardware.push((n, HardwareFault::DmaOverrun(arg(1)?))),
                    "crystal" => p.hardware.push((0, HardwareFault::Crystal(arg(0)?))),
                    other => bail!(
                        "unknown fault `{other}`; valid: drop, corrupt, duplicate, reorder, delay, disconnect \
                         (each also with a req- prefix), switch-open, switch-closed, saturated, laser-dead, stall, overrun, \
                         crystal"
                    ),
                }
            }
        }
        Ok(faults)
    }
}
