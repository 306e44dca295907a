//! The incidence plane at one θi in log-polar form (Belcour Figs 7–9,
//! Spieringhs Fig 7): the radius is log f_r in decades above the smallest
//! value drawn, the angle is θo (+ on the light's side), the retro and
//! mirror directions are marked, each sample carries its k = 2 error bar and
//! the fits are drawn over the data.

use super::{err, finite_runs, fr, in_plane, legend, PALETTE, STYLE};
use crate::fit::file::FittedBrdf;
use crate::fit::Dataset;
use crate::rounding::superscript;
use crate::uncertainty::K_COVERAGE;
use anyhow::Result;
use gonio_brdf::Directions;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The chart's polar frame: `decades` above `10^floor_exp`.
#[derive(Clone, Copy)]
struct Polar {
    floor_exp: i32,
    decades: f64,
}

impl Polar {
    /// The frame that holds every positive value of `values`.
    fn holding(values: impl Iterator<Item = f64>) -> Polar {
        let (lo, hi) = values
            .filter(|f| *f > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), f| (lo.min(f), hi.max(f)));
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (1e-3, 1.0) };
        let floor_exp = lo.log10().floor() as i32;
        let decades = (hi / 10f64.powi(floor_exp)).log10().ceil().max(1.0);
        Polar { floor_exp, decades }
    }

    /// Decades of `f` above the floor (0 below it).
    fn radius(self, f: f64) -> f64 {
        let floor = 10f64.powi(self.floor_exp);
        (f.max(floor) / floor).log10()
    }

    /// The point at angle `t` (degrees) and radius `r`.
    fn xy(t: f64, r: f64) -> (f64, f64) {
        (r * t.to_radians().sin(), r * t.to_radians().cos())
    }
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

pub fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, data: &Dataset, ti: f64, fits: &[FittedBrdf]) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    // (signed θo, f_r, expanded uncertainty of f_r)
    let points: Vec<(f64, f64, Option<f64>)> = data
        .observations
        .iter()
        .filter_map(|o| {
            let u = o.sigma.map(|s| K_COVERAGE * s / o.unit_factor(data.units));
            in_plane(o).map(|t| (t, fr(o, data), u))
        })
        .filter(|p| p.1 > 0.0)
        .collect();
    let curve = |m: &FittedBrdf| -> Vec<(f64, f64)> {
        (-890..=890)
            .map(|k| {
                let t = k as f64 / 10.0;
                let f = m.eval(&Directions::from_degrees(ti, t.abs(), if t >= 0.0 { 0.0 } else { 180.0 }));
                (t, f)
            })
            .collect()
    };
    let curves: Vec<Vec<(f64, f64)>> = fits.iter().map(curve).collect();
    let polar = Polar::holding(points.iter().map(|p| p.1).chain(curves.iter().flatten().map(|p| p.1)));
    let decades = polar.decades;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("incidence plane, θi = {ti}°: log-polar f_r (sr⁻¹)"),
            ("sans-serif", STYLE.title),
        )
        .margin(10)
        .build_cartesian_2d(-decades * 1.12..decades * 1.12, -0.06 * decades..decades * 1.1)
        .map_err(err)?;
    grid(&mut chart, polar, ti)?;
    for (k, (m, c)) in fits.iter().zip(&curves).enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        for (j, run) in finite_runs(c).into_iter().enumerate() {
            let series = chart
                .draw_series(LineSeries::new(
                    run.iter().map(|&(t, f)| Polar::xy(t, polar.radius(f))),
                    color.stroke_width(2),
                ))
                .map_err(err)?;
            if j == 0 {
                series
                    .label(m.name())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
            }
        }
    }
    // The error bars: radial, from f − U to f + U (U = k·u, k = 2).
    chart
        .draw_series(points.iter().filter_map(|&(t, f, u)| {
            u.map(|u| {
                PathElement::new(
                    vec![Polar::xy(t, polar.radius(f - u)), Polar::xy(t, polar.radius(f + u))],
                    BLACK.mix(0.7),
                )
            })
        }))
        .map_err(err)?;
    chart
        .draw_series(
            points
                .iter()
                .map(|&(t, f, _)| Circle::new(Polar::xy(t, polar.radius(f)), 3, BLACK.filled())),
        )
        .map_err(err)?
        .label(if points.iter().any(|p| p.2.is_some()) {
            format!("measured (± U, k = {K_COVERAGE})")
        } else {
            "measured".to_string()
        })
        .legend(|(x, y)| Circle::new((x + 10, y), 3, BLACK.filled()));
    legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
    Ok(())
}

/// The frame: a ring per decade, θo every 15° (+ on the light's side), and
/// the retro and mirror directions of `ti`.
fn grid<DB: DrawingBackend>(chart: &mut Chart<'_, DB>, polar: Polar, ti: f64) -> Result<()> {
    let decades = polar.decades;
    let label = TextStyle::from(("sans-serif", STYLE.label).into_font());
    let grey = RGBColor(200, 200, 200);
    for d in 1..=decades as i32 {
        let ring: Vec<(f64, f64)> = (-90..=90).map(|a| Polar::xy(a as f64, d as f64)).collect();
        chart.draw_series(LineSeries::new(ring, grey)).map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("10{} sr⁻¹", superscript(polar.floor_exp + d)),
                (0.02 * decades, d as f64 - 0.02 * decades),
                label.clone(),
            )))
            .map_err(err)?;
    }
    for t in (-90..=90).step_by(15) {
        let t = t as f64;
        chart
            .draw_series(LineSeries::new(vec![(0.0, 0.0), Polar::xy(t, decades)], grey.mix(0.6)))
            .map_err(err)?;
        let h = match t {
            t if t > 5.0 => HPos::Left,
            t if t < -5.0 => HPos::Right,
            _ => HPos::Center,
        };
        let at = Polar::xy(t, decades * 1.03);
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{t}°"),
                at,
                label.clone().pos(Pos::new(h, VPos::Bottom)),
            )))
            .map_err(err)?;
    }
    chart
        .draw_series(std::iter::once(Text::new(
            "θo (°), + on the side of the light",
            (-decades * 1.1, -0.04 * decades),
            label.clone(),
        )))
        .map_err(err)?;
    for (t, name) in [(ti, "retro"), (-ti, "mirror")] {
        chart
            .draw_series(LineSeries::new(
                vec![(0.0, 0.0), Polar::xy(t, decades)],
                RGBColor(120, 120, 120).stroke_width(1),
            ))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(name, Polar::xy(t + 2.0, decades * 0.9), label.clone())))
            .map_err(err)?;
    }
    Ok(())
}
