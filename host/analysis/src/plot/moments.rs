//! The paper's Fig. 6 for one material: the retro lobe's ratio of axis
//! variances r against θi, back plane (red, plain) and light-view plane
//! (green, dashed); 0 is an isotropic lobe. A hollow marker is an
//! under-sampled lobe (samples more than a lobe width apart in it).

use super::{err, legend, register_font, STYLE};
use crate::moments::{Entry, Parametrization};
use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Writes `dir/moments.svg` and `.png`; returns both paths.
pub fn render(entries: &[Entry], dir: &Path) -> Result<Vec<PathBuf>> {
    register_font()?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let svg = dir.join("moments.svg");
    draw(&SVGBackend::new(&svg, (760, 520)).into_drawing_area(), entries)?;
    let png = dir.join("moments.png");
    draw(&BitMapBackend::new(&png, (760, 520)).into_drawing_area(), entries)?;
    Ok(vec![svg, png])
}

/// `(θi, r)` and whether the lobe is under-sampled.
fn points(entries: &[Entry], p: Parametrization) -> Vec<((f64, f64), bool)> {
    entries
        .iter()
        .filter(|e| e.parametrization == p)
        .filter_map(|e| e.moments.as_ref().map(|m| ((e.theta_i_deg, m.r), m.under_sampled)))
        .filter(|((_, r), _)| r.is_finite())
        .collect()
}

fn marker(color: RGBColor, under_sampled: bool) -> ShapeStyle {
    if under_sampled {
        color.stroke_width(2)
    } else {
        color.filled()
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, entries: &[Entry]) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let top = Parametrization::BOTH
        .iter()
        .flat_map(|&p| points(entries, p))
        .fold(1.0f64, |m, ((_, r), _)| m.max(1.1 * r));
    let mut chart = ChartBuilder::on(root)
        .caption("retro lobe isotropy: ratio of the axis variances", ("sans-serif", STYLE.title))
        .margin(12)
        .x_label_area_size(3 * STYLE.label)
        .y_label_area_size(4 * STYLE.label)
        .build_cartesian_2d(0.0..90.0, 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("incidence θi (°)")
        .y_desc("r = (σ²max − σ²min) / σ²min")
        .label_style(("sans-serif", STYLE.label))
        .axis_desc_style(("sans-serif", STYLE.label))
        .draw()
        .map_err(err)?;
    let (red, green) = (RGBColor(200, 30, 30), RGBColor(30, 140, 50));
    let back = points(entries, Parametrization::Back);
    chart
        .draw_series(LineSeries::new(back.iter().map(|(p, _)| *p), red.stroke_width(2)))
        .map_err(err)?
        .label("back")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red.stroke_width(2)));
    chart
        .draw_series(back.iter().map(|&(p, u)| Circle::new(p, 4, marker(red, u))))
        .map_err(err)?;
    let view = points(entries, Parametrization::LightView);
    chart
        .draw_series(DashedLineSeries::new(view.iter().map(|(p, _)| *p), 8, 5, green.stroke_width(2)))
        .map_err(err)?
        .label("light-view")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], green.stroke_width(2)));
    chart
        .draw_series(
            view.iter()
                .map(|&((x, y), u)| Rectangle::new([(x - 0.8, y - 0.012 * top), (x + 0.8, y + 0.012 * top)], marker(green, u))),
        )
        .map_err(err)?;
    if back.iter().chain(&view).any(|(_, u)| *u) {
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label("hollow: under-sampled (gap > σ)")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, BLACK.stroke_width(2)));
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}
