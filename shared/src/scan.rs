//! A scan: a grid of isotropic geometries, expanded point by point on the
//! head (it never holds the whole grid) and on the host (to check coverage).
//!
//! A sweep scan ([`SweepScan`]) measures while moving: its positions are
//! rows ([`SweepRow`]), one per incidence and Δφ of the grid, each swept by
//! the arm alone and yielding many swept samples, and at each incidence the
//! retro direction, which no row reaches, measured at rest.
//!
//! Two orders matter. The *canonical index* enumerates the grid θi-major,
//! then θo, then Δφ, each incidence's pattern points after its grid (a
//! sweep scan's: θi-major, then the retro point, the rows, the pattern);
//! files and resumption use it. The *visit order* is the order
//! the head visits positions in: the host orders the positions and sends
//! the order in chunks of canonical indices (below); the head takes any
//! order. The host's `scan_order` (gonio-acquire) puts each incidence's unreachable
//! points first and the reachable ones along a short path of move times;
//! where it does not search (a sweep scan's positions, an incidence too large
//! for the search) it sends [`ScanSpec::index_at_order`]: a serpentine that
//! reverses the θo sweep on every other Δφ row and the Δφ sweep on every
//! other incidence, so the arm and the sample never swing back across the
//! whole range between neighbours (where the patterns and a sweep scan's
//! rows come: [`ScanSpec::index_at_order`]).

use crate::fault::{Fault, Field};
use crate::geometry::Geometry;
use crate::lobe_pattern::LobePatterns;
use crate::row_turn;
use crate::sample::Sample;
use crate::sweep::{SweepLobe, SweptSample};
use postcard_schema::Schema;
use serde::{Deserialize, Serialize};

/// The protocol since which a sweep scan's positions lie where they do now
/// (each incidence's retro point first, its rows turned evenly about the
/// laser): a scan recorded under an earlier one is not resumed under this.
/// Raised only when `ScanSpec::visit` or `index_at_order` move a sweep
/// scan's positions.
pub const SWEEP_LAYOUT_SINCE: u16 = 12;

/// Inclusive, evenly stepped range of angles (degrees).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AngleRange {
    pub start_deg: f32,
    pub stop_deg: f32,
    pub step_deg: f32,
}

impl AngleRange {
    pub const fn new(start_deg: f32, stop_deg: f32, step_deg: f32) -> Self {
        Self {
            start_deg,
            stop_deg,
            step_deg,
        }
    }

    /// Number of values, or `None` for a malformed range.
    pub fn count(&self) -> Option<u32> {
        let (a, b, s) = (self.start_deg, self.stop_deg, self.step_deg);
        if !(a.is_finite() && b.is_finite() && s.is_finite()) || s <= 0.0 || b < a || b - a > 360.0 {
            return None;
        }
        // The stop value is included when it lies on the grid (to 1e-4 step).
        // A step so small that the count saturates is refused, not wrapped
        // (found by the dispatch fuzzer).
        let steps = ((b - a) / s + 1.0e-4) as u32;
        steps.checked_add(1)
    }

    /// The k-th value.
    pub fn at(&self, k: u32) -> f32 {
        self.start_deg + k as f32 * self.step_deg
    }
}

/// Why a text is not an [`AngleRange`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RangeTextError {
    /// Not three fields separated by colons.
    Shape,
    /// A field is not a finite number.
    Number,
    /// The range is empty or malformed ([`AngleRange::count`]).
    Empty,
}

impl core::fmt::Display for RangeTextError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            RangeTextError::Shape => "not START:STOP:STEP",
            RangeTextError::Number => "START, STOP and STEP must be finite numbers (degrees)",
            RangeTextError::Empty => "empty or malformed (STEP > 0, START ≤ STOP, span ≤ 360°)",
        })
    }
}

impl core::error::Error for RangeTextError {}

/// `START:STOP:STEP` in degrees, STOP included (the command line's form).
impl core::str::FromStr for AngleRange {
    type Err = RangeTextError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let mut fields = s.split(':').map(|x| x.trim().parse::<f32>().ok().filter(|v| v.is_finite()));
        let (Some(a), Some(b), Some(c), None) = (fields.next(), fields.next(), fields.next(), fields.next()) else {
            return Err(RangeTextError::Shape);
        };
        let (Some(a), Some(b), Some(c)) = (a, b, c) else {
            return Err(RangeTextError::Number);
        };
        let r = AngleRange::new(a, b, c);
        r.count().map(|_| r).ok_or(RangeTextError::Empty)
    }
}

/// The scan asked of the head.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanSpec {
    pub theta_i_deg: heapless::Vec<f32, 8>,
    pub theta_o: AngleRange,
    pub dphi: AngleRange,
    /// Visit-order position to start at: 0 for a new scan, the first missing
    /// position to resume an interrupted one.
    pub first_order: u32,
    /// Measure while moving, row by row ([`SweepRow`]), instead of stopping
    /// at every point (absent in a scan.json of an earlier gonio).
    #[serde(default)]
    pub sweep: Option<SweepScan>,
    /// Rings about the retro and the mirror direction of every incidence,
    /// measured at rest besides the grid or the rows ([`LobePatterns`];
    /// absent in a scan.json of an earlier gonio).
    #[serde(default)]
    pub patterns: Option<LobePatterns>,
}

/// How a sweep scan sweeps its rows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepScan {
    /// Top speed of the arm (deg/s); a row goes at most at the arm's limit.
    pub speed_dps: f32,
    /// Chop periods per swept sample (`SweepRequest::periods_per_sample`).
    pub periods_per_sample: u16,
    /// Slower across the material's narrow lobes ([`SweepLobe`]); absent,
    /// every row at `speed_dps` from end to end (and in a scan.json of an
    /// earlier gonio).
    #[serde(default)]
    pub lobe: Option<SweepLobe>,
}

/// One row of a sweep scan: the sample held at incidence `theta_i_deg`, the
/// arm alone sweeps the view along the great circle through the retro
/// direction that meets the horizon at azimuth `dphi_deg`, from just outside
/// the blind zone around the retro direction out to `theta_o_stop_deg`
/// (`outward`) or back. Moving one axis, the cheapest path the kinematics
/// offer, keeps θi exact; the rows of a scan, turned evenly about the laser
/// ([`crate::row_turn`]: the Δφ step apart over a whole circle), cover the
/// hemisphere densest around the retro direction, where retroreflectors put
/// their light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepRow {
    pub theta_i_deg: f32,
    pub dphi_deg: f32,
    pub theta_o_stop_deg: f32,
    pub outward: bool,
    pub speed_dps: f32,
    pub periods_per_sample: u16,
    pub lobe: Option<SweepLobe>,
}

/// θ at and beyond which a direction lies in or behind the sample's plane.
const HORIZON_DEG: f32 = 90.0;

/// What one visit position of a scan is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Visit {
    /// A point, measured at rest.
    Point(Geometry),
    /// A row, measured while sweeping.
    Row(SweepRow),
}

/// What a scan asks for before any bound: its incidences, its θo and Δφ
/// values, and the pattern points of each incidence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Asked {
    pub incidences: u32,
    pub theta_o: u32,
    pub dphi: u32,
    pub pattern_points: u32,
}

impl Asked {
    /// `incidences × (θo × Δφ + pattern points)`: a grid's positions (a
    /// sweep scan's with its θo span counted too), held to
    /// [`ScanSpec::POSITIONS_MAX`].
    pub fn positions(&self) -> u64 {
        u64::from(self.incidences) * (u64::from(self.theta_o) * u64::from(self.dphi) + u64::from(self.pattern_points))
    }
}

/// The shape of a validated grid: per incidence, `n_to × n_dp` grid
/// positions (a sweep scan's: its retro point and its rows, `1 × (rows + 1)`)
/// and then `n_pat` pattern points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Dims {
    n_ti: u32,
    n_to: u32,
    n_dp: u32,
    n_pat: u32,
}

impl Dims {
    /// Grid positions of one incidence.
    fn base(&self) -> u32 {
        self.n_to * self.n_dp
    }

    /// Positions of one incidence, its patterns' included.
    fn block(&self) -> u32 {
        self.base() + self.n_pat
    }
}

impl ScanSpec {
    /// The Belcour et al. grid: θi ∈ {15, 30, 60}°, θo 0–90° step 3°,
    /// Δφ −180°..180° step 10°.
    pub fn belcour() -> Self {
        let mut theta_i_deg = heapless::Vec::new();
        for t in [15.0, 30.0, 60.0] {
            // Capacity 8 > 3.
            let _ = theta_i_deg.push(t);
        }
        Self {
            theta_i_deg,
            theta_o: AngleRange::new(0.0, 90.0, 3.0),
            dphi: AngleRange::new(-180.0, 180.0, 10.0),
            first_order: 0,
            sweep: None,
            patterns: None,
        }
    }

    /// The Belcour grid with the reference lobe patterns
    /// ([`LobePatterns::cea`]) at each incidence: what `gonio scan` and
    /// `gonio demo` measure by default.
    pub fn belcour_with_patterns() -> Self {
        Self {
            patterns: Some(LobePatterns::cea()),
            ..Self::belcour()
        }
    }

    /// What the scan asks for; `None` for no incidence, one not finite, or
    /// a malformed range or pattern.
    pub fn asked(&self) -> Option<Asked> {
        if self.theta_i_deg.is_empty() || self.theta_i_deg.iter().any(|t| !t.is_finite()) {
            return None;
        }
        let pattern_points = match &self.patterns {
            Some(p) => p.count()?,
            None => 0,
        };
        Some(Asked {
            incidences: self.theta_i_deg.len() as u32,
            theta_o: self.theta_o.count()?,
            dphi: self.dphi.count()?,
            pattern_points,
        })
    }

    fn dims(&self) -> Result<Dims, Fault> {
        let bad = Err(Fault::InvalidValue(Field::ScanRange));
        let Some(asked) = self.asked() else {
            return bad;
        };
        let (n_ti, n_to, n_dp, n_pat) = (asked.incidences, asked.theta_o, asked.dphi, asked.pattern_points);
        // Bounded so every index fits in u32 with room to spare (a sweep
        // scan's with its θo span counted too: one bound for every scan).
        if asked.positions() > u64::from(Self::POSITIONS_MAX) {
            return bad;
        }
        if self.sweep.is_none() {
            return Ok(Dims { n_ti, n_to, n_dp, n_pat });
        }
        // A sweep scan's positions are, per incidence, its retro point
        // (column 0) and its rows (one θo "column" each, columns 1..), and a
        // row needs a θo short of the horizon to run to.
        if self.row_stop().is_none() {
            return bad;
        }
        Ok(Dims {
            n_ti,
            n_to: 1,
            n_dp: n_dp + 1,
            n_pat,
        })
    }

    /// The most positions one scan holds (a grid's points and its
    /// patterns', over every incidence).
    pub const POSITIONS_MAX: u32 = 10_000_000;

    /// Checks the grid and the start position; returns the number of
    /// positions (points, or a sweep scan's retro points and rows).
    pub fn validate(&self) -> Result<u32, Fault> {
        let d = self.dims()?;
        let n = d.n_ti * d.block();
        if self.first_order > n {
            return Err(Fault::InvalidValue(Field::ScanStart));
        }
        Ok(n)
    }

    /// A sweep scan's retro points, one an incidence, among its positions
    /// (0 for a grid, whose points are all of them).
    pub fn retro_points(&self) -> u32 {
        match self.sweep {
            Some(_) => self.theta_i_deg.len() as u32,
            None => 0,
        }
    }

    /// The lobe patterns' points among its positions, every incidence's.
    pub fn pattern_points(&self) -> u32 {
        self.dims().map_or(0, |d| d.n_ti * d.n_pat)
    }

    /// A sweep scan's rows among its positions (0 for a grid).
    pub fn rows(&self) -> u32 {
        match self.sweep {
            Some(_) => self.len().saturating_sub(self.retro_points() + self.pattern_points()),
            None => 0,
        }
    }

    /// Number of positions (0 for an invalid spec).
    pub fn len(&self) -> u32 {
        self.validate().unwrap_or(0)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Splits `i` into the incidence (outermost) and the position within
    /// its block, for an `i` inside the scan.
    fn locate(&self, i: u32) -> Option<(Dims, u32, u32)> {
        let d = self.dims().ok()?;
        let block = d.block();
        if i >= d.n_ti * block {
            return None;
        }
        Some((d, i / block, i % block))
    }

    /// The pattern point `k` of incidence `a`.
    fn pattern_point(&self, a: u32, k: u32) -> Option<Geometry> {
        self.patterns.as_ref()?.point(self.theta_i_deg[a as usize], k)
    }

    /// The geometry of canonical index `index`: a grid point, or a pattern
    /// point after its incidence's grid (`None` in a sweep scan, whose
    /// positions are mostly rows: [`ScanSpec::visit`]).
    pub fn point(&self, index: u32) -> Option<Geometry> {
        if self.sweep.is_some() {
            return None;
        }
        let (d, a, rest) = self.locate(index)?;
        if rest >= d.base() {
            return self.pattern_point(a, rest - d.base());
        }
        let (b, c) = (rest / d.n_dp, rest % d.n_dp);
        Some(Geometry::new(self.theta_i_deg[a as usize], self.theta_o.at(b), self.dphi.at(c)))
    }

    /// What canonical index `index` is when visited at position `order`: a
    /// point, or in a sweep scan an incidence's retro point (measured at
    /// rest through the beam splitter, where no row reaches: rows begin
    /// beyond the blind zone around it), a pattern point (measured at rest)
    /// or one of its rows (θi of the grid, its rows turned evenly about the
    /// laser across the Δφ span, [`crate::row_turn`], out to θo's last value
    /// short of 90°). An incidence's retro point is visited first, then its
    /// pattern, then its rows, the first outward from the retro direction
    /// and each next one back the other way, so consecutive rows join near
    /// the retro direction or near the horizon ([`ScanSpec::index_at_order`]).
    pub fn visit(&self, index: u32, order: u32) -> Option<Visit> {
        let Some(how) = self.sweep else {
            return self.point(index).map(Visit::Point);
        };
        let (d, a, c) = self.locate(index)?;
        let stop = self.row_stop()?;
        if c >= d.base() {
            return self.pattern_point(a, c - d.base()).map(Visit::Point);
        }
        let ti = self.theta_i_deg[a as usize];
        let Some(row) = c.checked_sub(1) else {
            return Some(Visit::Point(Geometry::new(ti, ti, 0.0)));
        };
        let rows = d.n_dp - 1;
        Some(Visit::Row(SweepRow {
            theta_i_deg: ti,
            dphi_deg: row_turn::row_dphi_deg(ti, self.dphi.at(0), self.dphi.at(rows - 1), row, rows),
            theta_o_stop_deg: stop,
            // The row's rank among the incidence's rows in visit order.
            outward: (order % d.block()).saturating_sub(d.n_pat) % 2 == 1,
            speed_dps: how.speed_dps,
            periods_per_sample: how.periods_per_sample,
            lobe: how.lobe,
        }))
    }

    /// θo's last value short of the horizon, where a sweep scan's rows end
    /// (`None` when even its first is not): found in a few steps, not by
    /// looking through the span (up to 10⁷ values).
    fn row_stop(&self) -> Option<f32> {
        let (r, n) = (&self.theta_o, self.theta_o.count()?);
        // (A NaN start is refused by `count`.)
        if r.start_deg >= HORIZON_DEG {
            return None;
        }
        // The estimate, then a step either way for the rounding.
        let guess = (((HORIZON_DEG - r.start_deg) / r.step_deg) as u32).min(n - 1);
        (guess.saturating_sub(1)..=guess.saturating_add(1).min(n - 1))
            .rev()
            .map(|k| r.at(k))
            .find(|&t| t < HORIZON_DEG)
    }

    /// Canonical index of the point visited at position `order`: a grid's
    /// points row by row of θo, Δφ's way back on every other one, then the
    /// incidence's pattern azimuth by azimuth ([`LobePatterns::visited`]); a
    /// sweep scan's retro point first at each incidence, then its pattern,
    /// then its rows, Δφ's way back at every other incidence.
    pub fn index_at_order(&self, order: u32) -> Option<u32> {
        let (d, a, p) = self.locate(order)?;
        let first = a * d.block();
        let pattern = |k: u32| self.patterns.as_ref().and_then(|pat| pat.visited(k)).map(|k| d.base() + k);
        if self.sweep.is_some() {
            let c = match p {
                0 => 0,
                p if p <= d.n_pat => pattern(p - 1)?,
                p => match p - d.n_pat {
                    r if a % 2 == 0 => r,
                    r => d.n_dp - r,
                },
            };
            return Some(first + c);
        }
        if p >= d.base() {
            return pattern(p - d.base()).map(|c| first + c);
        }
        let (row, col) = (p / d.n_to, p % d.n_to);
        let c = if a % 2 == 0 { row } else { d.n_dp - 1 - row };
        let b = if row % 2 == 0 { col } else { d.n_to - 1 - col };
        Some(first + b * d.n_dp + c)
    }
}

/// The head's answer to a scan request.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanAccepted {
    pub points: u32,
    pub first_order: u32,
    /// Number of this scan run on the head since power-up: its `Finished`
    /// and `Stopped` events carry it, so a late one of an earlier run is
    /// told apart.
    pub run: u32,
}

/// Streamed on the scan-event topic alongside the samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ScanEvent {
    /// A measured point.
    Sample(Sample),
    /// A sample of the row a sweep scan is sweeping (its `scan` says which).
    SweptSample(SweptSample),
    /// A sweep scan's row is done: `samples` swept samples were sent for it
    /// (consecutive `seq`), which the host checks before it keeps them.
    Swept { index: u32, order: u32, samples: u32 },
    /// A point that cannot be reached, and why; nothing moved for it.
    Skipped { index: u32, order: u32, reason: Fault },
    /// Every point from `first_order` on was visited.
    Finished { run: u32, measured: u32, skipped: u32 },
    /// The scan stopped early; `next_order` resumes it.
    Stopped { run: u32, next_order: u32, reason: Fault },
    /// The scan is held at `next_order`, at the host's request (`None`) or
    /// for a fault (host silence): `gonio/continue` carries it on there with
    /// its queue as it was; a new scan replaces it.
    Paused { run: u32, next_order: u32, reason: Option<Fault> },
}

/// Visit positions a chunk of the visit order carries: 32 indices of at most five
/// bytes each keep a chunk inside one frame.
pub const VISIT_CHUNK: usize = 32;
/// Visit positions the head holds ahead of the point it is at (1 KiB). At
/// 150 ms or more per measured point, 256 points carry a scan through 38 s
/// of an absent host; when they run out the head waits, its host watch
/// running.
pub const VISIT_QUEUE: usize = 256;

/// The next stretch of a scan's visit order, from the host (which orders it:
/// f64 at GHz, where the head would spend seconds;
/// `docs/decisions/001-host-plans-the-visit-order.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VisitChunk {
    /// The run it belongs to (`ScanAccepted::run`), so a late chunk of an
    /// earlier run is refused; 0 for the scan the head holds now (a script
    /// that sends its frames blind).
    pub run: u32,
    /// Visit position of the first index.
    pub first_order: u32,
    /// Canonical indices (`ScanSpec::point`) in visit order.
    pub indices: heapless::Vec<u32, VISIT_CHUNK>,
}

/// What the head holds of the visit order after a chunk.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Schema)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VisitsQueued {
    /// Visit position the next chunk must start at: a chunk that starts
    /// elsewhere, or the part of one that does not fit, is not taken.
    pub next_order: u32,
    /// Positions the queue can take now.
    pub room: u32,
}
