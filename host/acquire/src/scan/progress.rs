//! What the operator sees of a running scan, on the terminal's bar and on
//! the live page ([`Live`]): the positions done, what was measured and what
//! was unreachable, and the time left. The time left is
//! the plan's own estimate of the positions still to visit (head time, from
//! `scan_order::duration`), scaled by how the head time spent so far
//! compares with the plan's estimate of the positions done: the ratio
//! starts at 1 and earns its weight as the scan runs, so the figure neither
//! starts from a wall-clock guess nor swings on the first few points.

use super::live::{Live, Update};
use crate::operator::Operator;
use gonio_scan_dir::run::hms;
use gonio_shared::{Geometry, Signal};
use indicatif::{ProgressBar, ProgressStyle};

/// Head time (s) the correction is held at 1 for, at most: the first
/// minute of a scan says little about its rate (the first move, ranging).
const PRIOR_S: f64 = 60.0;

/// The progress of one session of a scan.
pub struct Progress {
    bar: ProgressBar,
    /// Head time still to run before each position from `first` (s), then 0.
    left_s: Vec<f64>,
    first: u32,
    live: Live,
}

impl Progress {
    /// A scan's progress from position `first`, with the plan's `left_s`
    /// ([`crate::scan_order::duration::time_left_s`]); `items` names the
    /// positions (points, positions).
    pub fn new(operator: Operator, left_s: Vec<f64>, first: u32, items: &str, live: Live) -> Progress {
        let positions = left_s.len().saturating_sub(1) as u64;
        let bar = if operator != Operator::Terminal {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(positions)
        };
        bar.set_style(
            ProgressStyle::with_template(&format!("{{spinner}} scanning [{{bar:24}}] {{pos}}/{{len}} {items}, {{msg}}"))
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        Progress { bar, left_s, first, live }
    }

    /// The plan's estimate of the whole session (head time, s).
    pub fn estimate_s(&self) -> f64 {
        self.left_s.first().copied().unwrap_or(0.0)
    }

    /// The head time left (s) with position `next` the next to visit, after
    /// `spent_s` of head time in this session.
    pub fn left_s(&self, next: u32, spent_s: f64) -> f64 {
        let k = (next.saturating_sub(self.first) as usize).min(self.left_s.len().saturating_sub(1));
        let (total, left) = (self.estimate_s(), self.left_s.get(k).copied().unwrap_or(0.0));
        let done = total - left;
        let prior = PRIOR_S.min(0.05 * total);
        let rate = match done + prior {
            w if w > 0.0 => (spent_s + prior) / w,
            _ => 1.0,
        };
        left * rate
    }

    /// Shows position `next` as the next to visit.
    pub fn update(&self, next: u32, spent_s: f64, measured: u32, unreachable: u32) {
        let left_s = self.left_s(next, spent_s);
        self.bar.set_position(next.saturating_sub(self.first) as u64);
        self.bar
            .set_message(format!("{measured} measured, {unreachable} unreachable, {} left", hms(left_s)));
        self.live.publish(Update::Progress {
            done: next,
            of: self.first + self.left_s.len().saturating_sub(1) as u32,
            measured,
            unreachable,
            left_s,
        });
    }

    /// Shows a measured position on the live page.
    pub fn sample(&self, at: &Geometry, signal: &Signal) {
        self.live.publish(Update::Sample {
            theta_i_deg: at.theta_i_deg,
            theta_o_deg: at.theta_o_deg,
            dphi_deg: at.dphi_deg,
            signal_v: signal.amplitude_v,
            gain_v_per_a: signal.gain_v_per_a,
        });
    }

    /// The live page's side: state to show, requests to obey.
    pub fn live(&self) -> &Live {
        &self.live
    }

    /// Runs `f` (a notice) with the bar hidden.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.bar.suspend(f)
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 100 positions of 10 s each, from position 20 of a resumed scan.
    fn even() -> Progress {
        Progress::new(
            Operator::Silent,
            (0..=100).rev().map(|k| 10.0 * k as f64).collect(),
            20,
            "points",
            Live::default(),
        )
    }

    #[test]
    fn on_plan_the_time_left_is_the_plans() {
        let p = even();
        assert_eq!(p.estimate_s(), 1000.0);
        assert_eq!(p.left_s(20, 0.0), 1000.0);
        assert!((p.left_s(70, 500.0) - 500.0).abs() < 1e-9);
        assert_eq!(p.left_s(120, 1000.0), 0.0);
    }

    #[test]
    fn a_slower_head_scales_what_is_left_once_it_has_run_a_while() {
        let p = even();
        // Twice as slow as planned: the first few seconds barely move the
        // estimate, half-way it is the head's rate.
        let early = p.left_s(21, 20.0);
        assert!((early / 990.0 - 1.0) < 0.25, "{early}");
        let half = p.left_s(70, 1000.0);
        assert!((half / 1000.0 - 1.0).abs() < 0.1, "{half}");
    }

    #[test]
    fn at_a_steady_rate_the_figure_closes_on_the_truth() {
        let p = even();
        // A head 1.5 × slower than planned: 15 s a position.
        let error: Vec<f64> = (20..120)
            .map(|k| p.left_s(k, 15.0 * (k - 20) as f64) / (15.0 * (120 - k) as f64) - 1.0)
            .map(f64::abs)
            .collect();
        assert!(error.windows(2).all(|w| w[1] <= w[0]), "{error:?}");
        assert!(error[50] < 0.05, "half-way: {}", error[50]);
    }
}
