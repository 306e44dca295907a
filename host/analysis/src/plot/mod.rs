//! Pictures of a data set and its fits (PNG and SVG, `plotters`), per
//! incidence angle: the incidence-plane plot of the papers (Belcour Figs 7–9,
//! Spieringhs Fig 7) in log-polar form with the retro and mirror directions
//! marked, a projected-hemisphere map `(θo·cosΔφ, θo·sinΔφ)` of the
//! measured values, and a map of the first fit's relative residuals.

pub mod coefficients;

use crate::fit::{data::theta_in, Dataset, Observation};
use anyhow::{anyhow, Context, Result};
use gonio_brdf::{Directions, Material};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;
use std::path::{Path, PathBuf};

/// The font every picture's text is set in, shipped with the tool
/// (`host/analysis/assets`, DejaVu licence) so the PNGs render the same everywhere.
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

pub(crate) fn register_font() -> Result<()> {
    static ONCE: std::sync::Once = std::sync::Once::new();
    let mut result = Ok(());
    ONCE.call_once(|| {
        result = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).map_err(|_| anyhow!("the bundled font is invalid"));
    });
    result
}

/// Samples within this of Δφ = 0 or 180° are in the incidence plane.
const IN_PLANE_DEG: f64 = 5.0;
pub(crate) const PALETTE: [RGBColor; 5] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

pub(crate) fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing: {e:?}")
}

/// Signed viewing angle in the incidence plane (+ on the light's side), or
/// `None` off the plane.
fn in_plane(o: &Observation) -> Option<f64> {
    let d = o.dphi.to_degrees().rem_euclid(360.0);
    if d.min(360.0 - d) <= IN_PLANE_DEG {
        Some(o.theta_o.to_degrees())
    } else if (d - 180.0).abs() <= IN_PLANE_DEG {
        Some(-o.theta_o.to_degrees())
    } else {
        None
    }
}

/// `f_r` of the observations, in sr⁻¹ whatever the file's units.
fn fr(o: &Observation, data: &Dataset) -> f64 {
    o.value / o.unit_factor(data.units)
}

/// The pictures drawn per incidence angle.
#[derive(Debug, Clone, Copy)]
enum Picture {
    Plane,
    Hemisphere,
    Residuals,
}

impl Picture {
    fn name(self) -> &'static str {
        match self {
            Picture::Plane => "plane",
            Picture::Hemisphere => "hemisphere",
            Picture::Residuals => "residuals",
        }
    }

    fn size(self) -> (u32, u32) {
        match self {
            Picture::Plane => (1000, 560),
            _ => (720, 720),
        }
    }

    fn draw<DB: DrawingBackend>(self, root: &DrawingArea<DB, Shift>, data: &Dataset, ti: f64, fits: &[Material]) -> Result<()> {
        match self {
            Picture::Plane => incidence_plane(root, data, ti, fits),
            Picture::Hemisphere => hemisphere(root, data, ti, None),
            Picture::Residuals => hemisphere(root, data, ti, fits.first()),
        }
    }
}

/// Draws every picture for every incidence angle (residuals only with a
/// fit); returns the files written.
pub fn render(data: &Dataset, fits: &[Material], dir: &Path) -> Result<Vec<PathBuf>> {
    register_font()?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let kinds: &[Picture] = if fits.is_empty() {
        &[Picture::Plane, Picture::Hemisphere]
    } else {
        &[Picture::Plane, Picture::Hemisphere, Picture::Residuals]
    };
    let mut files = Vec::new();
    for ti in data.incidence_angles_deg() {
        let at = data.filter(|o| theta_in(o.theta_i, &[ti]));
        for &kind in kinds {
            let stem = format!("{}-{ti}", kind.name());
            let p = dir.join(format!("{stem}.svg"));
            let root = SVGBackend::new(&p, kind.size()).into_drawing_area();
            kind.draw(&root, &at, ti, fits)?;
            root.present().map_err(err)?;
            drop(root);
            files.push(p);
            let p = dir.join(format!("{stem}.png"));
            let root = BitMapBackend::new(&p, kind.size()).into_drawing_area();
            kind.draw(&root, &at, ti, fits)?;
            root.present().map_err(err)?;
            drop(root);
            files.push(p);
        }
    }
    Ok(files)
}

fn incidence_plane<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, data: &Dataset, ti: f64, fits: &[Material]) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let points: Vec<(f64, f64)> = data
        .observations
        .iter()
        .filter_map(|o| in_plane(o).map(|t| (t, fr(o, data))))
        .filter(|p| p.1 > 0.0)
        .collect();
    let curve = |m: &Material| -> Vec<(f64, f64)> {
        (-890..=890)
            .map(|k| {
                let t = k as f64 / 10.0;
                let f = m.eval(&Directions::from_degrees(ti, t.abs(), if t >= 0.0 { 0.0 } else { 180.0 }));
                (t, f)
            })
            .collect()
    };
    let curves: Vec<Vec<(f64, f64)>> = fits.iter().map(curve).collect();
    let all = points.iter().chain(curves.iter().flatten()).map(|p| p.1).filter(|f| *f > 0.0);
    let (lo, hi) = all.fold((f64::INFINITY, 0.0f64), |(lo, hi), f| (lo.min(f), hi.max(f)));
    let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (1e-3, 1.0) };
    let floor = 10f64.powf(lo.log10().floor());
    let decades = (hi / floor).log10().ceil().max(1.0);
    let radius = |f: f64| (f.max(floor) / floor).log10();
    let to_xy = |t: f64, f: f64| (radius(f) * t.to_radians().sin(), radius(f) * t.to_radians().cos());
    let mut chart = ChartBuilder::on(root)
        .caption(format!("incidence plane, θi = {ti}° (log-polar f_r, sr⁻¹)"), ("sans-serif", 22))
        .margin(12)
        .build_cartesian_2d(-decades * 1.05..decades * 1.05, -0.02 * decades..decades * 1.08)
        .map_err(err)?;
    for d in 1..=decades as i32 {
        let ring: Vec<(f64, f64)> = (-90..=90)
            .map(|a| (d as f64 * (a as f64).to_radians().sin(), d as f64 * (a as f64).to_radians().cos()))
            .collect();
        chart.draw_series(LineSeries::new(ring, RGBColor(200, 200, 200))).map_err(err)?;
        let label = format!("{:.0e}", floor * 10f64.powi(d));
        chart
            .draw_series(std::iter::once(Text::new(label, (0.02 * decades, d as f64), ("sans-serif", 13))))
            .map_err(err)?;
    }
    for (t, name, color) in [(ti, "retro", RGBColor(120, 120, 120)), (-ti, "mirror", RGBColor(120, 120, 120))] {
        let end = (decades * t.to_radians().sin(), decades * t.to_radians().cos());
        chart
            .draw_series(LineSeries::new(vec![(0.0, 0.0), end], color.stroke_width(1)))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(name, (end.0 * 1.02, end.1 * 1.02), ("sans-serif", 15))))
            .map_err(err)?;
    }
    for (k, (m, c)) in fits.iter().zip(&curves).enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(c.iter().map(|&(t, f)| to_xy(t, f)), color.stroke_width(2)))
            .map_err(err)?
            .label(m.model.name())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .draw_series(points.iter().map(|&(t, f)| Circle::new(to_xy(t, f), 3, BLACK.filled())))
        .map_err(err)?
        .label("measured")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, BLACK.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Projected hemisphere at one θi: measured `log10 f_r` (viridis), or with
/// `fit`, the relative residual `(f_m − f_r)/f_r` (blue −20 % … red +20 %).
fn hemisphere<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, data: &Dataset, ti: f64, fit: Option<&Material>) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let title = match fit {
        None => format!("measured log₁₀ f_r, θi = {ti}° (θo·cosΔφ, θo·sinΔφ)"),
        Some(m) => format!("residual (measured − {})/{}, θi = {ti}°", m.model.name(), m.model.name()),
    };
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .build_cartesian_2d(-95.0..95.0, -95.0..95.0)
        .map_err(err)?;
    let edge: Vec<(f64, f64)> = (0..=360)
        .map(|a| (90.0 * (a as f64).to_radians().cos(), 90.0 * (a as f64).to_radians().sin()))
        .collect();
    chart.draw_series(LineSeries::new(edge, BLACK)).map_err(err)?;
    let values: Vec<(f64, f64, f64)> = data
        .observations
        .iter()
        .map(|o| {
            let (x, y) = (o.theta_o.to_degrees() * o.dphi.cos(), o.theta_o.to_degrees() * o.dphi.sin());
            let v = match fit {
                None => fr(o, data).max(1e-12).log10(),
                Some(m) => {
                    let model = m.eval(&o.directions());
                    ((fr(o, data) - model) / model.abs().max(1e-12)).clamp(-0.2, 0.2)
                }
            };
            (x, y, v)
        })
        .collect();
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v.2), hi.max(v.2)));
    let color = |v: f64| -> RGBColor {
        match fit {
            None => ViridisRGB::get_color_normalized(v, lo, hi.max(lo + 1e-9)),
            Some(_) => {
                let u = v / 0.2;
                let w = |c: f64| (255.0 * (1.0 - u.abs()) + c * u.abs()) as u8;
                if u < 0.0 {
                    RGBColor(w(31.0), w(119.0), w(180.0))
                } else {
                    RGBColor(w(214.0), w(39.0), w(40.0))
                }
            }
        }
    };
    chart
        .draw_series(values.iter().map(|&(x, y, v)| Circle::new((x, y), 5, color(v).filled())))
        .map_err(err)?;
    let light = (ti, 0.0);
    chart
        .draw_series(std::iter::once(Cross::new(light, 7, BLACK.stroke_width(2))))
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(Text::new("retro", (ti + 2.0, 3.0), ("sans-serif", 14))))
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(Cross::new((-ti, 0.0), 7, BLACK.stroke_width(2))))
        .map_err(err)?;
    chart
        .draw_series(std::iter::once(Text::new("mirror", (-ti + 2.0, 3.0), ("sans-serif", 14))))
        .map_err(err)?;
    let legend = match fit {
        None => format!("colour: log₁₀ f_r from {lo:.2} to {hi:.2}"),
        Some(_) => "colour: −20 % (blue) … 0 (white) … +20 % (red)".to_string(),
    };
    chart
        .draw_series(std::iter::once(Text::new(legend, (-90.0, -93.0), ("sans-serif", 14))))
        .map_err(err)?;
    Ok(())
}
