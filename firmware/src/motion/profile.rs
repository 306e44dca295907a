//! A rest-to-rest move of `n` steps under an acceleration limit `a`
//! (steps/s²) and a speed cap per stretch of the way (steps/s): a chain of
//! trapezoids. An ordinary move has one stretch: constant acceleration,
//! cruise, constant deceleration (triangular when `n` is too short to reach
//! its cap). A sweep scan's row has a few, slower where a lobe of the
//! material is narrow ([`crate::sweep::row_levels`]): the move slows down
//! before it enters a slow stretch and speeds up once it has left it, never
//! stopping between. Step k (1-based) happens when the position reaches k.

use heapless::Vec;

/// Most stretches a profile has: a row's slow retro and mirror zones and
/// the fast stretches between and after them.
pub const MAX_LEVELS: usize = 5;

/// How the speed changes along a phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Accelerating,
    Cruising,
    Decelerating,
}

/// One smooth piece of a profile: a ramp at `a`, or a cruise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phase {
    pub kind: Kind,
    /// Where it starts and ends (steps, real) and when it starts (s).
    pub x0: f64,
    pub x1: f64,
    /// Speed at its start and at its end (steps/s).
    pub v0: f64,
    pub v1: f64,
    /// Step k's time is `c0 + √(c1 + 2k/a)` accelerating, `c0 + c1·k`
    /// cruising, `c0 − √(c1 − 2k/a)` decelerating: the planner's cost per
    /// step time is one multiplication, one addition and a square root in
    /// f64, as a ramp from rest costs.
    c0: f64,
    c1: f64,
}

impl Phase {
    /// The phase from `x0` to `x1` starting at `t0` (s), from speed `v0` to `v1`.
    fn new(kind: Kind, (x0, x1): (f64, f64), t0: f64, (v0, v1): (f64, f64), a: f64) -> Self {
        // Accelerating: t = t0 + (√(v0² + 2a(k − x0)) − v0)/a; decelerating,
        // from its end t1 = t0 + (v0 − v1)/a: t = t1 − (√(v1² + 2a(x1 − k)) − v1)/a.
        let (c0, c1) = match kind {
            Kind::Accelerating => (t0 - v0 / a, (v0 * v0 - 2.0 * a * x0) / (a * a)),
            Kind::Cruising => (t0 - x0 / v0, 1.0 / v0),
            Kind::Decelerating => (t0 + v0 / a, (v1 * v1 + 2.0 * a * x1) / (a * a)),
        };
        Phase {
            kind,
            x0,
            x1,
            v0,
            v1,
            c0,
            c1,
        }
    }
}

/// The analytical profile, in seconds.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    pub n: u32,
    pub a: f64,
    two_over_a: f64,
    phases: Vec<Phase, { 3 * MAX_LEVELS }>,
    total: f64,
}

impl Profile {
    /// One stretch at up to `v`. `v` and `a` must be positive and finite (a
    /// `HeadConfig`'s are).
    pub fn new(n: u32, v: f64, a: f64) -> Self {
        Self::levels(n, a, [(n, v)])
    }

    /// Consecutive stretches `(last step, speed cap)`: the first from the
    /// start, the last to step `n` whatever its given end. Stretches beyond
    /// [`MAX_LEVELS`] join the last one kept, at the lowest of their caps.
    /// Each junction is passed at the lower cap of its two stretches, or
    /// lower where the acceleration limit asks it (the stretches before and
    /// after too short to ramp): no stretch is ever run above its cap.
    pub fn levels(n: u32, a: f64, caps: impl IntoIterator<Item = (u32, f64)>) -> Self {
        // Stretch ends (steps) and caps, empty stretches dropped.
        let mut ends: Vec<(f64, f64), MAX_LEVELS> = Vec::new();
        let mut from = 0u32;
        let mut caps = caps.into_iter().peekable();
        while let Some((end, cap)) = caps.next() {
            let last = caps.peek().is_none();
            let end = if last { n } else { end.min(n) };
            if end <= from && !last {
                continue;
            }
            if ends.is_full() {
                let last = ends.len() - 1;
                ends[last] = (n as f64, ends[last].1.min(cap));
            } else {
                let _ = ends.push((end as f64, cap));
            }
            from = end;
        }
        if let Some(last) = ends.last_mut() {
            last.0 = n as f64;
        }
        // Junction speeds: the lower cap, then what the ramps allow both ways.
        let m = ends.len();
        let mut u = [0.0f64; MAX_LEVELS + 1];
        for j in 1..m {
            u[j] = ends[j - 1].1.min(ends[j].1);
        }
        let start = |j: usize| if j == 0 { 0.0 } else { ends[j - 1].0 };
        for j in 1..m {
            u[j] = u[j].min(libm::sqrt(u[j - 1] * u[j - 1] + 2.0 * a * (ends[j - 1].0 - start(j - 1))));
        }
        for j in (1..m).rev() {
            u[j] = u[j].min(libm::sqrt(u[j + 1] * u[j + 1] + 2.0 * a * (ends[j].0 - start(j))));
        }
        let mut phases = Vec::new();
        let mut t = 0.0;
        for (j, &(x1, cap)) in ends.iter().enumerate() {
            let (x0, v0, v1) = (start(j), u[j], u[j + 1]);
            let len = x1 - x0;
            let peak = cap.min(libm::sqrt(a * len + 0.5 * (v0 * v0 + v1 * v1))).max(v0.max(v1));
            let up = (peak * peak - v0 * v0) / (2.0 * a);
            let down = (peak * peak - v1 * v1) / (2.0 * a);
            let cruise = (len - up - down).max(0.0);
            let pieces = [
                (Kind::Accelerating, up, v0, peak, (peak - v0) / a),
                (Kind::Cruising, cruise, peak, peak, cruise / peak),
                (Kind::Decelerating, down, peak, v1, (peak - v1) / a),
            ];
            let mut x = x0;
            for (kind, dx, s0, s1, dt) in pieces {
                // Rounding leaves a cruise of 10⁻¹² steps where a ramp meets
                // the next: no phase.
                if dx > 1e-9 {
                    let end = if kind == Kind::Decelerating { x1 } else { (x + dx).min(x1) };
                    // At most three a stretch: the capacity holds them.
                    let _ = phases.push(Phase::new(kind, (x, end), t, (s0, s1), a));
                    x = end;
                    t += dt;
                }
            }
        }
        Profile {
            n,
            a,
            two_over_a: 2.0 / a,
            phases,
            total: t,
        }
    }

    /// Time (s) of step `k` (1 ≤ k ≤ n) from the start of the move.
    pub fn step_time(&self, k: u32) -> f64 {
        match self.phases.iter().position(|p| k as f64 <= p.x1) {
            Some(i) => self.step_time_in(i, k),
            None => self.total,
        }
    }

    /// Time (s) of step `k`, which phase `i` holds: no search, for the
    /// planner that walks the phases in order.
    pub fn step_time_in(&self, i: usize, k: u32) -> f64 {
        let Some(p) = self.phases.get(i) else {
            return self.total;
        };
        let k = k as f64;
        match p.kind {
            Kind::Accelerating => p.c0 + libm::sqrt((p.c1 + k * self.two_over_a).max(0.0)),
            Kind::Cruising => p.c0 + p.c1 * k,
            Kind::Decelerating => p.c0 - libm::sqrt((p.c1 - k * self.two_over_a).max(0.0)),
        }
    }

    /// The phases in order.
    pub fn phases(&self) -> &[Phase] {
        &self.phases
    }

    pub fn duration(&self) -> f64 {
        self.total
    }

    /// `Profile::new(n, v, a).duration()` without the profile: the same
    /// operations in the same order, so the same bits. The host's visit
    /// order and its lower bound ask it for every pair of positions (a
    /// default scan's 4 641 positions: a third of the demo's time went to
    /// building the profiles).
    pub fn rest_to_rest_s(n: u32, v: f64, a: f64) -> f64 {
        let len = n as f64;
        let peak = v.min(libm::sqrt(a * len + 0.0)).max(0.0);
        let ramp = peak * peak / (2.0 * a);
        let cruise = (len - ramp - ramp).max(0.0);
        let mut t = 0.0;
        if ramp > 1e-9 {
            t += peak / a;
        }
        if cruise > 1e-9 {
            t += cruise / peak;
        }
        if ramp > 1e-9 {
            t += peak / a;
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Speed between steps k and k + 1, from the schedule.
    fn speeds(p: &Profile) -> std::vec::Vec<f64> {
        (1..p.n).map(|k| 1.0 / (p.step_time(k + 1) - p.step_time(k))).collect()
    }

    #[test]
    fn the_rest_to_rest_time_is_the_profiles_to_the_bit() {
        for (v, a) in [(24_000.0, 60_000.0), (3_200.0, 8_000.0), (1e5, 1.5e3)] {
            for n in (0..2_000).chain((1..400).map(|k| k * 997)) {
                let whole = Profile::new(n, v, a).duration();
                assert_eq!(Profile::rest_to_rest_s(n, v, a).to_bits(), whole.to_bits(), "n {n}, v {v}, a {a}");
            }
        }
    }

    #[test]
    fn one_stretch_is_the_trapezoid() {
        // 30°/s, 60°/s² at 400 µsteps/°: 0.5 s ramps, 6 000 steps each.
        let p = Profile::new(36_000, 12_000.0, 24_000.0);
        assert!((p.duration() - 3.5).abs() < 1e-12);
        assert!((p.step_time(3_000) - 0.5).abs() < 1e-12);
        assert!((p.step_time(18_000) - 1.75).abs() < 1e-12);
        // Triangular: never reaches its cap.
        let p = Profile::new(1_000, 12_000.0, 24_000.0);
        assert!((p.duration() - 2.0 * (1_000.0 / 24_000.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(p.phases().len(), 2);
    }

    #[test]
    fn slow_stretches_are_run_at_their_cap_without_stopping() {
        let (a, fast, slow) = (24_000.0, 12_000.0, 4_000.0);
        let caps = [(10_000, slow), (30_000, fast), (40_000, slow), (60_000, fast)];
        let p = Profile::levels(60_000, a, caps);
        let v = speeds(&p);
        for (k, s) in v.iter().enumerate() {
            let step = k as u32 + 1;
            let cap = caps.iter().find(|c| step < c.0).map_or(fast, |c| c.1);
            assert!(*s <= cap * (1.0 + 1e-6), "step {step}: {s} above {cap}");
        }
        // Within the slow stretches, at their cap; never at rest between.
        assert!((v[5_000] - slow).abs() < 1e-3 * slow);
        assert!((v[35_000] - slow).abs() < 1e-3 * slow);
        assert!((v[20_000] - fast).abs() < 1e-3 * fast);
        let min_between = v[10_000..40_000].iter().copied().fold(f64::INFINITY, f64::min);
        assert!(min_between >= slow * 0.999, "{min_between}");
        // Duration: ramps plus cruises, checked against the speeds' sum.
        let sum: f64 = v.iter().map(|s| 1.0 / s).sum::<f64>() + p.step_time(1);
        assert!((sum - p.duration()).abs() < 1e-6, "{sum} vs {}", p.duration());
        assert!(p.duration() < 60_000.0 / slow);
    }

    #[test]
    fn short_stretches_are_passed_below_their_neighbours_caps() {
        // Too short to reach either cap: the profile stays continuous.
        let caps = [(100, 1_500.0), (300, 12_000.0), (400, 1_500.0)];
        let p = Profile::levels(400, 24_000.0, caps);
        let mut last = 0.0;
        for k in 1..=400 {
            let t = p.step_time(k);
            assert!(t > last && t.is_finite(), "step {k}");
            last = t;
        }
        assert!((p.step_time(400) - p.duration()).abs() < 1e-12);
        // Never above a stretch's cap, nor faster than the ramps allow: the
        // outer stretches cruise at their cap (reached in 47 steps), the
        // middle one, too short to reach its own, peaks where speeding up from
        // 1 500 meets slowing down to it, √(a·200 + 1 500²) = 2 655 steps/s.
        let v = speeds(&p);
        for (k, v) in v.iter().enumerate() {
            let step = k as u32 + 1;
            let cap = caps.iter().find(|c| step < c.0).map_or(1_500.0, |c| c.1);
            assert!(*v <= cap * (1.0 + 1e-6) && *v <= 2_655.2, "step {step}: {v}");
        }
        assert!(
            (v[70] - 1_500.0).abs() < 1.0 && (v[350] - 1_500.0).abs() < 1.0,
            "{} {}",
            v[70],
            v[350]
        );
        assert!(v[199] > 2_640.0, "{}", v[199]);
    }

    #[test]
    fn too_many_stretches_join_the_last_at_its_lowest_cap() {
        let caps: std::vec::Vec<(u32, f64)> = (1..=8).map(|i| (i * 1_000, if i == 7 { 1_000.0 } else { 8_000.0 })).collect();
        let p = Profile::levels(8_000, 24_000.0, caps.iter().copied());
        let v = speeds(&p);
        assert!(v[6_000..].iter().all(|&s| s <= 1_000.0 * (1.0 + 1e-6)));
    }
}
