//! The projected hemisphere at one θi, `(θo·cosΔφ, θo·sinΔφ)` with the
//! light's side to the right: the measured f_r, or a fit's residuals in
//! units of each sample's σ, interpolated between the samples (inverse
//! distance over the four nearest) and left grey where no sample is near.
//! Rings of θo and spokes of Δφ are labelled in degrees, the colour bar in
//! the value's unit.

use super::colour_scale::{ColourScale, Scale, LEVELS};
use super::{err, fr, STYLE};
use crate::fit::file::FittedBrdf;
use crate::fit::{Dataset, Observation};
use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Side of a map cell (degrees of projected angle).
const CELL: f64 = 1.5;
/// Samples weighed in each cell.
const NEAREST: usize = 4;

/// A map ready to draw (its interpolation done once for both formats).
pub struct Map {
    title: String,
    scale: ColourScale,
    /// Runs of equal colour along a row of cells: `(y, x0, x1, level)`.
    runs: Vec<(f64, f64, f64, usize)>,
    samples: Vec<(f64, f64)>,
    /// Cells farther than this from every sample are left grey (degrees).
    gap: f64,
    ti: f64,
}

fn projected(o: &Observation) -> (f64, f64) {
    let t = o.theta_o.to_degrees();
    (t * o.dphi.cos(), t * o.dphi.sin())
}

/// The measured f_r of `data` (one θi) on `scale`, over `range` (sr⁻¹) or the data's.
pub fn measured(data: &Dataset, ti: f64, scale: Scale, range: Option<(f64, f64)>) -> Map {
    let values: Vec<f64> = data.observations.iter().map(|o| fr(o, data)).collect();
    let colours = ColourScale::fr(&values, scale, range);
    build(format!("measured f_r, θi = {ti}°"), colours, data, &values, ti)
}

/// The residuals of `fit`: in units of σ where every sample carries one,
/// relative otherwise.
pub fn residuals(data: &Dataset, ti: f64, fit: &FittedBrdf) -> Map {
    let name = fit.name();
    let model: Vec<f64> = data.observations.iter().map(|o| fit.eval(&o.directions())).collect();
    let sigmas: Option<Vec<f64>> = data
        .observations
        .iter()
        .map(|o| o.sigma.filter(|s| *s > 0.0).map(|s| s / o.unit_factor(data.units)))
        .collect();
    let measured = data.observations.iter().map(|o| fr(o, data));
    match sigmas {
        Some(s) => {
            let r: Vec<f64> = measured.zip(&model).zip(&s).map(|((m, f), s)| (m - f) / s).collect();
            build(
                format!("(measured − {name}) / σ, θi = {ti}°"),
                ColourScale::sigmas(&r),
                data,
                &r,
                ti,
            )
        }
        None => {
            let r: Vec<f64> = measured.zip(&model).map(|(m, f)| (m - f) / f.abs().max(1e-12)).collect();
            let title = format!("(measured − {name}) / {name}, θi = {ti}° (no σ in the data)");
            build(title, ColourScale::relative(&r), data, &r, ti)
        }
    }
}

fn build(title: String, scale: ColourScale, data: &Dataset, values: &[f64], ti: f64) -> Map {
    let samples: Vec<(f64, f64)> = data.observations.iter().map(projected).collect();
    // A sample without a value (a rational function's pole in a residual)
    // colours no cell.
    let (valued, positions): (Vec<(f64, f64)>, Vec<f64>) = samples
        .iter()
        .zip(values)
        .filter(|(_, v)| v.is_finite())
        .map(|(&p, &v)| (p, scale.level(v) as f64 + 0.5))
        .unzip();
    let gap = gap(&samples);
    let n = (180.0 / CELL).round() as i32;
    let mut runs = Vec::new();
    for row in 0..n {
        let y = -90.0 + row as f64 * CELL;
        let mut run: Option<(f64, usize)> = None;
        for col in 0..=n {
            let x = -90.0 + col as f64 * CELL;
            let (cx, cy) = (x + CELL / 2.0, y + CELL / 2.0);
            let level = (col < n && cx.hypot(cy) <= 90.0)
                .then(|| interpolate(&valued, &positions, (cx, cy), gap))
                .flatten()
                .map(|p| (p as usize).min(LEVELS - 1));
            match (run, level) {
                (Some((_, l)), Some(m)) if l == m => {}
                _ => {
                    if let Some((x0, l)) = run {
                        runs.push((y, x0, x, l));
                    }
                    run = level.map(|l| (x, l));
                }
            }
        }
    }
    Map {
        title,
        scale,
        runs,
        samples,
        gap,
        ti,
    }
}

/// The farthest a cell may be from its nearest sample and still be filled:
/// the 95th percentile of each sample's distance to its fourth neighbour,
/// so that the grid's own spacing (coarser in Δφ near the horizon) fills
/// and a hole in the scan does not.
fn gap(samples: &[(f64, f64)]) -> f64 {
    let mut d: Vec<f64> = samples
        .iter()
        .map(|&p| nearest(samples, p).get(NEAREST).map_or(f64::INFINITY, |n| n.0))
        .filter(|d| d.is_finite())
        .collect();
    if d.is_empty() {
        return 2.0;
    }
    d.sort_by(f64::total_cmp);
    d[((d.len() - 1) as f64 * 0.95) as usize].max(2.0)
}

/// The samples nearest `p` (distance, index), closest first; at most
/// `NEAREST + 1` (a sample's own position comes first when `p` is one).
fn nearest(samples: &[(f64, f64)], p: (f64, f64)) -> Vec<(f64, usize)> {
    // Ranked by squared distance, rooted once chosen: every cell of every
    // map scans every sample, and `hypot` there was 5 % of the demo's time.
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(NEAREST + 2);
    for (i, s) in samples.iter().enumerate() {
        let (dx, dy) = (s.0 - p.0, s.1 - p.1);
        let d2 = dx * dx + dy * dy;
        if best.len() <= NEAREST || d2 < best[NEAREST].0 {
            let at = best.partition_point(|b| b.0 <= d2);
            best.insert(at, (d2, i));
            best.truncate(NEAREST + 1);
        }
    }
    best.iter().map(|&(d2, i)| (d2.sqrt(), i)).collect()
}

/// Inverse-distance weighting of the four nearest samples, or `None` when
/// the nearest is farther than `gap`.
fn interpolate(samples: &[(f64, f64)], values: &[f64], p: (f64, f64), gap: f64) -> Option<f64> {
    let near = nearest(samples, p);
    if near.first().is_none_or(|n| n.0 > gap) {
        return None;
    }
    let (mut sum, mut weight) = (0.0, 0.0);
    for &(d, i) in near.iter().take(NEAREST) {
        let w = 1.0 / (d * d).max(1e-6);
        sum += w * values[i];
        weight += w;
    }
    Some(sum / weight)
}

pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, map: &Map) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let (_, h) = root.dim_in_pixel();
    let (area, bar) = root.split_horizontally(h);
    let mut chart = ChartBuilder::on(&area)
        .caption(&map.title, ("sans-serif", STYLE.title))
        .margin(8)
        .build_cartesian_2d(-122.0..122.0, -112.0..112.0)
        .map_err(err)?;
    let circle = |r: f64| -> Vec<(f64, f64)> {
        (0..=360)
            .map(|a| (r * (a as f64).to_radians().cos(), r * (a as f64).to_radians().sin()))
            .collect()
    };
    chart
        .draw_series(std::iter::once(Polygon::new(circle(90.0), RGBColor(232, 232, 232).filled())))
        .map_err(err)?;
    chart
        .draw_series(
            map.runs
                .iter()
                .map(|&(y, x0, x1, l)| Rectangle::new([(x0, y), (x1, y + CELL)], map.scale.colour(l).filled())),
        )
        .map_err(err)?;
    chart
        .draw_series(map.samples.iter().map(|&p| Circle::new(p, 1, BLACK.mix(0.35).filled())))
        .map_err(err)?;
    let label = TextStyle::from(("sans-serif", STYLE.label).into_font());
    for t in [30.0, 60.0, 90.0] {
        chart.draw_series(LineSeries::new(circle(t), BLACK.mix(0.6))).map_err(err)?;
        let a = 112f64.to_radians();
        chart
            .draw_series(std::iter::once(Text::new(
                format!("θo = {t}°"),
                (t * a.cos(), t * a.sin()),
                label.clone(),
            )))
            .map_err(err)?;
    }
    for d in (0..360).step_by(45) {
        let a = (d as f64).to_radians();
        chart
            .draw_series(LineSeries::new(vec![(0.0, 0.0), (90.0 * a.cos(), 90.0 * a.sin())], BLACK.mix(0.35)))
            .map_err(err)?;
        let text = if d == 0 { "Δφ = 0°".to_string() } else { format!("{d}°") };
        let (x, y) = (97.0 * a.cos(), 97.0 * a.sin());
        let anchor = label.clone().pos(Pos::new(
            if a.cos() > 0.3 {
                HPos::Left
            } else if a.cos() < -0.3 {
                HPos::Right
            } else {
                HPos::Center
            },
            VPos::Center,
        ));
        chart.draw_series(std::iter::once(Text::new(text, (x, y), anchor))).map_err(err)?;
    }
    for (x, name) in [(map.ti, "retro"), (-map.ti, "mirror")] {
        chart
            .draw_series(std::iter::once(Cross::new((x, 0.0), 7, WHITE.stroke_width(4))))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Cross::new((x, 0.0), 7, BLACK.stroke_width(2))))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(name, (x + 3.0, 11.0), label.clone())))
            .map_err(err)?;
    }
    chart
        .draw_series(std::iter::once(Text::new(
            format!("dots: samples; grey: none within {:.0}°", map.gap),
            (-121.0, -104.0),
            ("sans-serif", STYLE.label),
        )))
        .map_err(err)?;
    map.scale.draw_bar(&bar, STYLE.label)
}
