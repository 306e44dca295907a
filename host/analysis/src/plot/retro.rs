//! Near the retro peak at one θi: f_r against the observation angle α (the
//! angle between the light and the view), every sample within
//! `ALPHA_MAX_DEG` with its k = 2 error bar, and the fits along the
//! incidence plane towards the normal. A retroreflector's figure of merit
//! lives here, where a hemisphere map is a few pixels wide.

use super::{err, finite_runs, fr, legend, samples_with_bars, tick, PALETTE, STYLE};
use crate::fit::file::FittedBrdf;
use crate::fit::Dataset;
use crate::uncertainty::K_COVERAGE;
use anyhow::Result;
use gonio_brdf::frame::angle_between;
use gonio_brdf::Directions;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The widest observation angle drawn: beyond the outermost retro ring of
/// the reference head's lobe pattern (4.75°).
pub const ALPHA_MAX_DEG: f64 = 6.0;
/// Fewer samples than this near the peak draw no picture.
pub const MIN_SAMPLES: usize = 3;

/// `(α, f_r, U)` of the samples within `ALPHA_MAX_DEG` of the light.
pub fn near_peak(data: &Dataset) -> Vec<(f64, f64, Option<f64>)> {
    data.observations
        .iter()
        .filter_map(|o| {
            let d = o.directions();
            let alpha = angle_between(d.l, d.v).to_degrees();
            let u = o.sigma.map(|s| K_COVERAGE * s / o.unit_factor(data.units));
            (alpha <= ALPHA_MAX_DEG).then(|| (alpha, fr(o, data), u))
        })
        .filter(|p| p.1 > 0.0)
        .collect()
}

pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, data: &Dataset, ti: f64, fits: &[FittedBrdf]) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let points = near_peak(data);
    // A fit along the incidence plane, the view tilted from the light
    // towards the normal by α (through it, to Δφ = 180°, when α > θi).
    let along = |m: &FittedBrdf, a: f64| {
        let t = ti - a;
        m.eval(&Directions::from_degrees(ti, t.abs(), if t >= 0.0 { 0.0 } else { 180.0 }))
    };
    let curves: Vec<Vec<(f64, f64)>> = fits
        .iter()
        .map(|m| {
            (0..=600)
                .map(|k| k as f64 * ALPHA_MAX_DEG / 600.0)
                .map(|a| (a, along(m, a)))
                .collect()
        })
        .collect();
    let values = points
        .iter()
        .flat_map(|&(_, f, u)| [f, f + u.unwrap_or(0.0), f - u.unwrap_or(0.0)])
        .chain(curves.iter().flatten().map(|p| p.1));
    let (lo, hi) = values
        .filter(|f| *f > 0.0 && f.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), f| (lo.min(f), hi.max(f)));
    let (lo, hi) = if lo.is_finite() { (lo / 1.5, hi * 1.5) } else { (1e-3, 1.0) };
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("near the retro peak, θi = {ti}°: f_r against α"),
            ("sans-serif", STYLE.title),
        )
        .margin(10)
        .x_label_area_size(3 * STYLE.label)
        .y_label_area_size(5 * STYLE.label)
        .build_cartesian_2d(0.0..ALPHA_MAX_DEG, (lo..hi).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("observation angle α (°)")
        .y_desc("f_r (sr⁻¹)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", STYLE.label))
        .axis_desc_style(("sans-serif", STYLE.label))
        .light_line_style(WHITE)
        .draw()
        .map_err(err)?;
    for (k, (m, c)) in fits.iter().zip(&curves).enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        for (j, run) in finite_runs(c).into_iter().enumerate() {
            let series = chart
                .draw_series(LineSeries::new(run.iter().copied().filter(|p| p.1 > lo), colour.stroke_width(2)))
                .map_err(err)?;
            if j == 0 {
                series
                    .label(format!("{} (in the incidence plane)", m.name()))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            }
        }
    }
    let label = format!("measured, every Δφ about the light (± U, k = {K_COVERAGE})");
    samples_with_bars(&mut chart, &points, lo, BLACK, label)?;
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    Ok(())
}
