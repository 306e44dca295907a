//! f_r against θo at one θi, one curve per plane of view through the
//! normal (Δφ and Δφ + 180°, the latter to the left): Cartesian, log f_r,
//! each sample with its k = 2 error bar and the best fit drawn in the same
//! colour. The incidence plane (Δφ = 0°) is the first.

use super::{err, fr, legend, samples_with_bars, tick, STYLE};
use crate::fit::file::FittedBrdf;
use crate::fit::Dataset;
use crate::uncertainty::K_COVERAGE;
use anyhow::Result;
use gonio_brdf::Directions;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The planes drawn (Δφ mod 180°), each the data's nearest within 5°.
const PLANES: [f64; 4] = [0.0, 45.0, 90.0, 135.0];
const NEAR_DEG: f64 = 5.0;
const COLOURS: [RGBColor; 4] = [
    RGBColor(0, 0, 0),
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
];

/// `(signed θo, f_r, U)` of a plane, and the plane's Δφ.
type Cut = (f64, Vec<(f64, f64, Option<f64>)>);

/// The data's planes nearest `PLANES`: a sample at Δφ is in plane p when
/// Δφ ≡ p (θo counted +) or Δφ ≡ p + 180° (θo counted −), within 1°.
fn cuts(data: &Dataset) -> Vec<Cut> {
    // Rounded to 10⁻⁶° first, so that −180° read back from radians is 0°.
    let plane_of = |dphi: f64| ((dphi.to_degrees() * 1e6).round() / 1e6).rem_euclid(180.0);
    let mut found: Vec<f64> = Vec::new();
    for p in PLANES {
        let near = data
            .observations
            .iter()
            .map(|o| plane_of(o.dphi))
            .map(|q| (q, (q - p).abs().min(180.0 - (q - p).abs())))
            .filter(|(_, d)| *d <= NEAR_DEG)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((q, _)) = near.filter(|(q, _)| !found.iter().any(|f| (f - q).abs() < 1.0)) {
            found.push(q + 0.0); // no −0°
        }
    }
    found
        .into_iter()
        .map(|p| {
            let mut points: Vec<(f64, f64, Option<f64>)> = data
                .observations
                .iter()
                .filter_map(|o| {
                    let d = o.dphi.to_degrees().rem_euclid(360.0);
                    let off = |q: f64| (d - q).rem_euclid(360.0).min((q - d).rem_euclid(360.0));
                    let side = if off(p) < 1.0 {
                        1.0
                    } else if off(p + 180.0) < 1.0 {
                        -1.0
                    } else {
                        return None;
                    };
                    let u = o.sigma.map(|s| K_COVERAGE * s / o.unit_factor(data.units));
                    Some((side * o.theta_o.to_degrees(), fr(o, data), u))
                })
                .filter(|p| p.1 > 0.0)
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            (p, points)
        })
        .filter(|(_, points)| points.len() >= 3)
        .collect()
}

pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, data: &Dataset, ti: f64, fit: Option<&FittedBrdf>) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let cuts = cuts(data);
    let model = |p: f64, t: f64| -> f64 {
        let dphi = if t >= 0.0 { p } else { p + 180.0 };
        fit.map_or(f64::NAN, |m| m.eval(&Directions::from_degrees(ti, t.abs(), dphi)))
    };
    let values = cuts
        .iter()
        .flat_map(|(_, pts)| pts.iter().flat_map(|&(_, f, u)| [f - u.unwrap_or(0.0), f + u.unwrap_or(0.0), f]));
    let (lo, hi) = values
        .filter(|f| *f > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), f| (lo.min(f), hi.max(f)));
    let (lo, hi) = if lo.is_finite() { (lo / 1.5, hi * 1.5) } else { (1e-3, 1.0) };
    let mut chart = ChartBuilder::on(root)
        .caption(format!("f_r against θo per plane of view, θi = {ti}°"), ("sans-serif", STYLE.title))
        .margin(10)
        .x_label_area_size(3 * STYLE.label)
        .y_label_area_size(5 * STYLE.label)
        .build_cartesian_2d(-90.0..90.0, (lo..hi).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("θo (°): + at Δφ, − at Δφ + 180°")
        .y_desc("f_r (sr⁻¹)")
        .x_labels(13)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", STYLE.label))
        .axis_desc_style(("sans-serif", STYLE.label))
        .light_line_style(WHITE)
        .draw()
        .map_err(err)?;
    for (k, (p, points)) in cuts.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        samples_with_bars(&mut chart, points, lo, colour, format!("Δφ = {p:.0}° / {:.0}°", p + 180.0))?;
        if fit.is_some() {
            let line = (-890..=890)
                .map(|k| k as f64 / 10.0)
                .map(|t| (t, model(*p, t)))
                .filter(|v| v.1 > lo);
            chart.draw_series(LineSeries::new(line, colour.stroke_width(1))).map_err(err)?;
        }
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    if let Some(m) = fit {
        let note = TextStyle::from(("sans-serif", STYLE.label).into_font()).pos(Pos::new(HPos::Right, VPos::Top));
        chart
            .draw_series(std::iter::once(Text::new(
                format!("lines: {}; bars: ± U (k = {K_COVERAGE})", m.name()),
                (88.0, hi / 1.1),
                note,
            )))
            .map_err(err)?;
    }
    Ok(())
}
