//! R_A against the observation angle α, one curve per entrance angle β of
//! ASTM E810 (coplanar, ε = 0), as a report shows it: drawn solid where the
//! data hold the geometry (measured or interpolated), dashed where a model
//! carries it (extrapolated), with the k = 2 band shaded. A tape maker reads
//! off where the numbers are measurements and where they are not.

use super::{err, legend, register_font, PALETTE};
use crate::coefficients::{self, Provenance, Source, ASTM_APERTURES, ASTM_BETAS};
use crate::uncertainty::K_COVERAGE;
use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Observation angles drawn (degrees): from 0.05° to 4.75°, the reference
/// head's outermost retro ring, finer where the lobe changes fastest.
fn alphas() -> Vec<f64> {
    let mut a: Vec<f64> = (1..=20).map(|k| 0.05 * k as f64).collect();
    a.extend((1..=38).map(|k| 1.0 + 0.1 * k as f64).filter(|x| *x <= 4.75));
    a
}

/// One point of a curve: α, the value, its expanded uncertainty, and
/// whether the data hold it.
struct At {
    alpha: f64,
    value: f64,
    expanded: f64,
    held: bool,
}

/// Writes `dir/coefficients-ra.svg` and `.png`; returns the PNG's path.
pub fn render(source: &Source, dir: &Path) -> Result<PathBuf> {
    register_font()?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let curves: Vec<(f64, Vec<At>)> = ASTM_BETAS
        .iter()
        .map(|&beta| {
            let requests = coefficients::grid(&alphas(), &[beta], &[0.0], ASTM_APERTURES);
            let values = coefficients::compute(source, &requests)?;
            let at = values
                .iter()
                .filter(|c| c.estimate.value.is_finite() && c.estimate.value > 0.0)
                .map(|c| At {
                    alpha: c.request.geometry.alpha_deg,
                    value: c.estimate.value,
                    expanded: K_COVERAGE * c.estimate.u,
                    held: c.estimate.basis.as_ref().is_none_or(|b| b.provenance != Provenance::Extrapolated),
                })
                .collect();
            Ok((beta, at))
        })
        .collect::<Result<_>>()?;
    let svg = dir.join("coefficients-ra.svg");
    draw(&SVGBackend::new(&svg, (900, 620)).into_drawing_area(), &curves)?;
    let png = dir.join("coefficients-ra.png");
    draw(&BitMapBackend::new(&png, (900, 620)).into_drawing_area(), &curves)?;
    Ok(png)
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, curves: &[(f64, Vec<At>)]) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let all = curves.iter().flat_map(|(_, c)| c.iter());
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(lo, hi), a| {
        (lo.min((a.value - a.expanded).max(a.value / 10.0)), hi.max(a.value + a.expanded))
    });
    let (lo, hi) = if lo.is_finite() && hi > lo { (lo, hi) } else { (1e-3, 1.0) };
    let mut chart = ChartBuilder::on(root)
        .caption("R_A against the observation angle (coplanar, ε = 0°)", ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..4.8f64, (lo * 0.8..hi * 1.25).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("observation angle α (°)")
        .y_desc("R_A (cd·lx⁻¹·m⁻²)")
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(err)?;
    for (k, (beta, at)) in curves.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let band: Vec<(f64, f64)> = at
            .iter()
            .map(|a| (a.alpha, a.value + a.expanded))
            .chain(at.iter().rev().map(|a| (a.alpha, (a.value - a.expanded).max(lo * 0.8))))
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(band, color.mix(0.15))))
            .map_err(err)?;
        // Runs of one kind, each joined to the next so the curve is unbroken.
        let mut start = 0;
        while start < at.len() {
            let held = at[start].held;
            let end = (start..at.len()).find(|&i| at[i].held != held).unwrap_or(at.len());
            let run: Vec<(f64, f64)> = at[start..(end + 1).min(at.len())].iter().map(|a| (a.alpha, a.value)).collect();
            if held {
                chart.draw_series(LineSeries::new(run, color.stroke_width(3))).map_err(err)?;
            } else {
                chart
                    .draw_series(DashedLineSeries::new(run, 8, 6, color.stroke_width(2)))
                    .map_err(err)?;
            }
            start = end;
        }
        let label = match at.iter().all(|a| !a.held) {
            true => format!("β = {beta}° (extrapolated)"),
            false => format!("β = {beta}°"),
        };
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3)));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    Ok(())
}
