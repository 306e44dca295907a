//! Repeatability at a glance: each geometry's standard deviation over the
//! repeats against what the budget predicts for it (log–log, one colour
//! per θi), with the line where they agree and the band a sample standard
//! deviation of so few repeats spreads over (its 95 % interval for the
//! median number of repeats).

use super::{err, legend, register_font, tick, STYLE};
use crate::repeatability::Repeatability;
use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Writes `dir/repeatability.svg` and `.png`; returns both paths.
pub fn render(r: &Repeatability, dir: &Path) -> Result<Vec<PathBuf>> {
    register_font()?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let svg = dir.join("repeatability.svg");
    draw(&SVGBackend::new(&svg, (760, 620)).into_drawing_area(), r)?;
    let png = dir.join("repeatability.png");
    draw(&BitMapBackend::new(&png, (760, 620)).into_drawing_area(), r)?;
    Ok(vec![svg, png])
}

/// The 2.5 % and 97.5 % points of s/σ for `n` repeats of a normal value,
/// √(χ²(p; n−1)/(n−1)): χ² quantiles from the table for up to 5 degrees of
/// freedom, Wilson–Hilferty's cube-root approximation beyond (within 2 %).
fn band(n: usize) -> (f64, f64) {
    const CHI2: [(f64, f64); 5] = [(0.000982, 5.024), (0.0506, 7.378), (0.216, 9.348), (0.484, 11.143), (0.831, 12.833)];
    let k = n.max(2) - 1;
    if let Some(&(a, b)) = CHI2.get(k - 1) {
        return ((a / k as f64).sqrt(), (b / k as f64).sqrt());
    }
    let k = k as f64;
    let at = |z: f64| (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).max(0.0).powi(3).sqrt();
    (at(-1.959_964), at(1.959_964))
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, r: &Repeatability) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let positive: Vec<_> = r.geometries.iter().filter(|g| g.s_sr > 0.0).collect();
    let all = positive.iter().flat_map(|g| [g.s_sr, g.u_predicted_sr]);
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (lo, hi) = if lo.is_finite() { (lo / 2.0, hi * 2.0) } else { (1e-4, 1.0) };
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("repeatability of {} scans: s against the budget's prediction", r.scans.len()),
            ("sans-serif", STYLE.title),
        )
        .margin(12)
        .x_label_area_size(3 * STYLE.label)
        .y_label_area_size(6 * STYLE.label)
        .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("predicted σ of a repeat (sr⁻¹)")
        .y_desc("standard deviation of the repeats s (sr⁻¹)")
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", STYLE.label))
        .axis_desc_style(("sans-serif", STYLE.label))
        .draw()
        .map_err(err)?;
    let mut counts: Vec<usize> = r.geometries.iter().map(|g| g.n).collect();
    counts.sort_unstable();
    let (below, above) = band(counts.get(counts.len() / 2).copied().unwrap_or(2));
    let grey = RGBColor(120, 120, 120);
    chart
        .draw_series(LineSeries::new(vec![(lo, lo), (hi, hi)], BLACK.stroke_width(2)))
        .map_err(err)?
        .label("s = σ")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    for (f, label) in [(below, true), (above, false)] {
        let s = chart
            .draw_series(LineSeries::new(vec![(lo, lo * f), (hi, hi * f)], grey.stroke_width(1)))
            .map_err(err)?;
        if label {
            s.label(format!(
                "95 % of s for {} repeats",
                counts.get(counts.len() / 2).copied().unwrap_or(2)
            ))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(1)));
        }
    }
    let mut incidences: Vec<f64> = r.geometries.iter().map(|g| g.theta_i_deg).collect();
    incidences.sort_by(f64::total_cmp);
    incidences.dedup();
    for (k, ti) in incidences.iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        chart
            .draw_series(
                positive
                    .iter()
                    .filter(|g| g.theta_i_deg == *ti)
                    .map(|g| Circle::new((g.u_predicted_sr, g.s_sr), 3, colour.filled())),
            )
            .map_err(err)?
            .label(format!("θi = {ti}°"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::band;

    #[test]
    fn the_band_of_s_narrows_with_repeats() {
        // χ²(0.025; 2)/2 = 0.0253, χ²(0.975; 2)/2 = 3.689: √ → 0.159, 1.921.
        let (lo, hi) = band(3);
        assert!((lo - 0.159).abs() < 1e-3 && (hi - 1.921).abs() < 1e-3, "{lo} {hi}");
        // Seven repeats by the approximation: χ²(0.025; 6) = 1.237, χ²(0.975; 6) = 14.449.
        let (lo, hi) = band(7);
        let (a, b) = ((1.237f64 / 6.0).sqrt(), (14.449f64 / 6.0).sqrt());
        assert!((lo / a - 1.0).abs() < 0.02 && (hi / b - 1.0).abs() < 0.02, "{lo} {hi}");
        let (lo, hi) = band(30);
        assert!(lo > 0.7 && hi < 1.3, "{lo} {hi}");
    }
}
