//! A map's colour scale and the bar that reads it back: viridis for f_r (log
//! or linear, over a range the user chooses or the data's 1st to 99th
//! percentile, so that one mirror lobe does not darken the rest), and a
//! diverging blue–white–red for residuals in units of σ. Values beyond the
//! range take the colour of its end, and the bar's end label says so (≥, ≤).

use super::err;
use crate::rounding::{self, significant};
use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

/// How f_r maps to colour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Scale {
    /// log₁₀ f_r: a lobe and its diffuse floor side by side.
    #[default]
    Log,
    /// f_r itself: the lobe's shape, the floor dark.
    Linear,
}

/// What a map's colours mean.
#[derive(Debug, Clone)]
pub struct ColourScale {
    kind: Kind,
    lo: f64,
    hi: f64,
    /// Whether values fall below `lo` or above `hi` (drawn at the ends).
    clipped: (bool, bool),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Fr(Scale),
    /// Residuals in units of their σ, symmetric about zero.
    Sigmas,
    /// Relative residuals (measured − model)/model, where the data carry no σ.
    Relative,
}

/// How many colours a map is quantized to: beyond the eye's resolution on
/// viridis, and it lets a map draw runs of equal colour as one rectangle.
pub const LEVELS: usize = 96;

impl ColourScale {
    /// The scale of f_r values (sr⁻¹): `range` as given, else the 1st to
    /// 99th percentile of the positive values.
    pub fn fr(values: &[f64], scale: Scale, range: Option<(f64, f64)>) -> ColourScale {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite() && *x > 0.0).collect();
        v.sort_by(f64::total_cmp);
        let (lo, hi) = range.unwrap_or_else(|| match v.len() {
            0 => (1e-3, 1.0),
            n => (v[n / 100], v[(n - 1) - n / 100]),
        });
        let (lo, hi) = match scale {
            Scale::Log => (lo.max(1e-12), hi.max(lo * 1.01)),
            Scale::Linear if range.is_none() => (0.0, hi.max(1e-12)),
            Scale::Linear => (lo, hi.max(lo + 1e-12)),
        };
        Self::with(Kind::Fr(scale), lo, hi, values)
    }

    /// The scale of residuals in σ: ±3 σ, or wider to hold the 95th
    /// percentile of |r| (whole σ), at most ±20.
    pub fn sigmas(values: &[f64]) -> ColourScale {
        let half = percentile_abs(values, 0.95).ceil().clamp(3.0, 20.0);
        Self::with(Kind::Sigmas, -half, half, values)
    }

    /// The scale of relative residuals: ±10 %, or wider to the 95th
    /// percentile of |r| (whole 10 %), at most ±100 %.
    pub fn relative(values: &[f64]) -> ColourScale {
        let half = ((percentile_abs(values, 0.95) * 10.0).ceil() / 10.0).clamp(0.1, 1.0);
        Self::with(Kind::Relative, -half, half, values)
    }

    fn with(kind: Kind, lo: f64, hi: f64, values: &[f64]) -> ColourScale {
        let finite = values.iter().filter(|v| v.is_finite());
        let clipped = (
            finite.clone().any(|&v| v < lo * (1.0 - 1e-9)),
            finite.clone().any(|&v| v > hi * (1.0 + 1e-9)),
        );
        ColourScale { kind, lo, hi, clipped }
    }

    /// Where `v` sits along the bar, 0 to 1 (clamped).
    fn position(&self, v: f64) -> f64 {
        let t = |x: f64| match self.kind {
            Kind::Fr(Scale::Log) => x.max(1e-300).log10(),
            _ => x,
        };
        ((t(v) - t(self.lo)) / (t(self.hi) - t(self.lo))).clamp(0.0, 1.0)
    }

    /// The colour level of `v`, `0..LEVELS`.
    pub fn level(&self, v: f64) -> usize {
        ((self.position(v) * LEVELS as f64) as usize).min(LEVELS - 1)
    }

    /// The colour of a level.
    pub fn colour(&self, level: usize) -> RGBColor {
        let u = (level as f64 + 0.5) / LEVELS as f64;
        match self.kind {
            Kind::Fr(_) => ViridisRGB::get_color_normalized(u, 0.0, 1.0),
            Kind::Sigmas | Kind::Relative => diverging(2.0 * u - 1.0),
        }
    }

    /// What the bar measures, with its unit and scale.
    pub fn title(&self) -> String {
        match self.kind {
            Kind::Fr(Scale::Log) => "f_r (sr⁻¹), log scale".into(),
            Kind::Fr(Scale::Linear) => "f_r (sr⁻¹), linear scale".into(),
            Kind::Sigmas => "residual / σ (k = 1)".into(),
            Kind::Relative => "(measured − model) / model".into(),
        }
    }

    /// Tick values and labels along the bar.
    fn ticks(&self) -> Vec<(f64, String)> {
        let mut ticks: Vec<(f64, String)> = match self.kind {
            Kind::Fr(Scale::Log) => log_ticks(self.lo, self.hi),
            Kind::Relative => linear_ticks(self.lo, self.hi)
                .into_iter()
                .map(|v| (v, format!("{} %", super::tick(100.0 * v))))
                .collect(),
            _ => linear_ticks(self.lo, self.hi).into_iter().map(|v| (v, super::tick(v))).collect(),
        };
        // The ends are labelled with the range itself, marked where values
        // lie beyond it.
        let end = |v: f64, mark: &str| match self.kind {
            Kind::Relative => format!("{mark}{} %", significant(100.0 * v, 2)),
            _ => format!("{mark}{}", significant(v, 2)),
        };
        ticks.retain(|(v, _)| (self.position(*v) - 0.0).abs() > 0.06 && (self.position(*v) - 1.0).abs() > 0.06);
        ticks.push((self.lo, end(self.lo, if self.clipped.0 { "≤ " } else { "" })));
        ticks.push((self.hi, end(self.hi, if self.clipped.1 { "≥ " } else { "" })));
        ticks
    }

    /// Draws the bar, its ticks, labels and title into `area` (a strip at a
    /// map's right).
    pub fn draw_bar<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, font: u32) -> Result<()> {
        let (w, h) = area.dim_in_pixel();
        let (w, h) = (w as i32, h as i32);
        let (top, bottom, left, width) = (h / 8, h - h / 8, 10, (w / 6).max(18));
        for k in 0..LEVELS {
            let y0 = bottom - (bottom - top) * (k as i32 + 1) / LEVELS as i32;
            let y1 = bottom - (bottom - top) * k as i32 / LEVELS as i32;
            area.draw(&Rectangle::new([(left, y0), (left + width, y1)], self.colour(k).filled()))
                .map_err(err)?;
        }
        area.draw(&Rectangle::new([(left, top), (left + width, bottom)], BLACK.stroke_width(1)))
            .map_err(err)?;
        let style = ("sans-serif", font).into_font().color(&BLACK);
        for (v, label) in self.ticks() {
            let y = bottom - ((bottom - top) as f64 * self.position(v)).round() as i32;
            area.draw(&PathElement::new(vec![(left + width, y), (left + width + 6, y)], BLACK))
                .map_err(err)?;
            area.draw(&Text::new(label, (left + width + 9, y - font as i32 / 2), style.clone()))
                .map_err(err)?;
        }
        let title = ("sans-serif", font).into_font().color(&BLACK).transform(FontTransform::Rotate270);
        area.draw(&Text::new(self.title(), (w - font as i32 - 4, bottom), title))
            .map_err(err)?;
        Ok(())
    }
}

/// Blue (−1) through white (0) to red (+1).
fn diverging(u: f64) -> RGBColor {
    let a = u.abs().min(1.0);
    let (r, g, b) = if u < 0.0 { (31.0, 119.0, 180.0) } else { (214.0, 39.0, 40.0) };
    let w = |c: f64| (255.0 * (1.0 - a) + c * a).round() as u8;
    RGBColor(w(r), w(g), w(b))
}

fn percentile_abs(values: &[f64], p: f64) -> f64 {
    let mut a: Vec<f64> = values.iter().filter(|v| v.is_finite()).map(|v| v.abs()).collect();
    if a.is_empty() {
        return 0.0;
    }
    a.sort_by(f64::total_cmp);
    a[((a.len() - 1) as f64 * p).round() as usize]
}

/// Decades between `lo` and `hi`, with 2× and 5× when the range spans
/// fewer than two of them; labelled `10ⁿ`, `2×10ⁿ`.
fn log_ticks(lo: f64, hi: f64) -> Vec<(f64, String)> {
    let (a, b) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let steps: &[f64] = if b - a <= 2 { &[1.0, 2.0, 5.0] } else { &[1.0] };
    let mut ticks = Vec::new();
    for e in a..=b {
        for &m in steps {
            let v = m * 10f64.powi(e);
            if v >= lo && v <= hi {
                let power = format!("10{}", rounding::superscript(e));
                ticks.push((v, if m == 1.0 { power } else { format!("{m}×{power}") }));
            }
        }
    }
    ticks
}

/// Round values (1, 2 or 5 × 10ⁿ apart) between `lo` and `hi`, about five.
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let raw = (hi - lo) / 5.0;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p);
    let first = (lo / step).ceil() as i64;
    (first..).map(|k| k as f64 * step).take_while(|v| *v <= hi + 1e-9 * step).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_range_leaves_the_brightest_percent_out() {
        let mut v: Vec<f64> = (1..=1000).map(|k| k as f64 * 1e-3).collect();
        v.push(1e3); // one mirror sample
        let s = ColourScale::fr(&v, Scale::Log, None);
        assert!(s.hi < 1.01 && s.clipped.1, "{s:?}");
        assert_eq!(s.level(1e3), LEVELS - 1);
        assert_eq!(s.level(1e-9), 0);
    }

    #[test]
    fn log_ticks_are_decades_labelled_as_powers() {
        let t = log_ticks(3e-3, 40.0);
        let labels: Vec<&str> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(labels, ["10⁻²", "10⁻¹", "10⁰", "10¹"]);
        assert_eq!(log_ticks(0.15, 3.0).len(), 4); // 0.2, 0.5, 1, 2
    }

    #[test]
    fn residual_scales_are_symmetric_and_widen_to_the_data() {
        let s = ColourScale::sigmas(&[0.5, -1.0, 7.2, 0.1]);
        assert_eq!((s.lo, s.hi), (-8.0, 8.0));
        assert_eq!(s.level(0.0), LEVELS / 2);
        assert_eq!(linear_ticks(-3.0, 3.0), [-2.0, 0.0, 2.0]);
    }
}
