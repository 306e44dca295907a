//! Pictures of a data set and its fits (PNG and SVG, `plotters`), per
//! incidence angle: the incidence plane in log-polar form (`plane`), f_r
//! against θo per plane of view (`cuts`), f_r against the observation angle
//! near the retro peak (`retro`), the projected hemisphere of the measured
//! values (`hemisphere`) and of the first fit's residuals in σ. Every axis
//! has ticks and its unit, every map a colour bar, every sample its k = 2
//! error bar where the data carry σ; the text is sized for the report,
//! which shows the pictures at their own size.

pub mod coefficients;
pub mod colour_scale;
mod cuts;
mod hemisphere;
pub mod moments;
mod plane;
pub mod repeatability;
mod retro;

pub use colour_scale::Scale;

use crate::fit::file::FittedBrdf;
use crate::fit::{data::theta_in, Dataset, Observation};
use anyhow::{anyhow, Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use rayon::prelude::*;
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

/// A chart's legend, the same on every picture: the series' labels on a
/// light box in a corner, in the label size.
pub(crate) fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    at: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .position(at)
        .label_font(("sans-serif", STYLE.label))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)
}

/// A chart of f_r (log) against an angle, as `cuts` and `retro` draw them.
pub(crate) type FrChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::combinators::LogCoord<f64>>>;

/// Samples `(angle, f_r, U)` as dots in `colour`, each with its error bar
/// from f − U (no lower than `lo`, the axis' floor) to f + U, and `label`
/// in the legend.
pub(crate) fn samples_with_bars<'a, DB: DrawingBackend + 'a>(
    chart: &mut FrChart<'a, DB>,
    points: &[(f64, f64, Option<f64>)],
    lo: f64,
    colour: RGBColor,
    label: String,
) -> Result<()> {
    chart
        .draw_series(
            points
                .iter()
                .filter_map(|&(x, f, u)| u.map(|u| ErrorBar::new_vertical(x, (f - u).max(lo), f, f + u, colour.mix(0.7), 5))),
        )
        .map_err(err)?;
    chart
        .draw_series(points.iter().map(|&(x, f, _)| Circle::new((x, f), 3, colour.filled())))
        .map_err(err)?
        .label(label)
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, colour.filled()));
    Ok(())
}

/// An axis tick's label: three significant digits, no trailing zeros.
pub(crate) fn tick(v: f64) -> String {
    let s = crate::rounding::significant(v, 3);
    let trim = |m: &str| match m.contains('.') {
        true => m.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => m.to_string(),
    };
    match s.split_once('×') {
        Some((m, p)) => format!("{}×{p}", trim(m)),
        None => trim(&s),
    }
}

/// How the maps colour f_r.
#[derive(Debug, Clone, Copy, Default)]
pub struct Options {
    pub scale: Scale,
    /// The colour bar's range of f_r (sr⁻¹); the data's 1st to 99th
    /// percentile when `None`.
    pub range: Option<(f64, f64)>,
}

/// A colour range `LO:HI` of f_r (sr⁻¹): finite, with 0 < LO < HI (a log
/// scale needs it, and f_r is not negative).
pub fn colour_range(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = s.split_once(':').ok_or_else(|| format!("`{s}` is not LO:HI"))?;
    let num = |x: &str| x.trim().parse::<f64>().map_err(|_| format!("`{x}` is not a number"));
    let (lo, hi) = (num(lo)?, num(hi)?);
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi) {
        return Err(format!("{lo}:{hi} must be finite with 0 < LO < HI (sr⁻¹)"));
    }
    Ok((lo, hi))
}

/// Text sizes (pixels), for pictures shown at their own size.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Style {
    pub title: u32,
    pub label: u32,
}

pub(crate) const STYLE: Style = Style { title: 21, label: 16 };

/// The pictures drawn per incidence angle, in the order a report shows them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Picture {
    Plane,
    Cuts,
    Retro,
    Hemisphere,
    Residuals,
}

impl Picture {
    pub const ALL: [Picture; 5] = [
        Picture::Plane,
        Picture::Cuts,
        Picture::Retro,
        Picture::Hemisphere,
        Picture::Residuals,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Picture::Plane => "plane",
            Picture::Cuts => "cuts",
            Picture::Retro => "retro",
            Picture::Hemisphere => "hemisphere",
            Picture::Residuals => "residuals",
        }
    }

    /// What the picture shows, for a caption.
    pub fn describe(self) -> &'static str {
        match self {
            Picture::Plane => "incidence plane, log-polar (data ± U and the best fits; retro and mirror directions marked)",
            Picture::Cuts => "f_r against θo per plane of view (data ± U, the best fit as lines)",
            Picture::Retro => "f_r against the observation angle α near the retro peak",
            Picture::Hemisphere => "projected hemisphere (θo·cosΔφ, θo·sinΔφ) of the measured f_r, interpolated",
            Picture::Residuals => "the best fit's residuals in units of each sample's σ",
        }
    }

    /// The picture named `name` (a file stem's first part).
    pub fn named(name: &str) -> Option<Picture> {
        Picture::ALL.into_iter().find(|p| p.name() == name)
    }

    fn size(self) -> (u32, u32) {
        match self {
            Picture::Hemisphere | Picture::Residuals => (700, 580),
            _ => (780, 540),
        }
    }
}

/// A picture with what it needs computed once for both formats.
enum Prepared {
    Plane,
    Cuts,
    Retro,
    Map(hemisphere::Map),
}

/// A curve cut where it has no value (a rational function's pole): its runs
/// of finite points, each drawn on its own so that no line bridges the gap.
fn finite_runs(curve: &[(f64, f64)]) -> Vec<&[(f64, f64)]> {
    curve.split(|p| !p.1.is_finite()).filter(|run| !run.is_empty()).collect()
}

fn prepare(kind: Picture, data: &Dataset, ti: f64, fits: &[FittedBrdf], o: &Options) -> Option<Prepared> {
    match kind {
        Picture::Plane => Some(Prepared::Plane),
        Picture::Cuts => Some(Prepared::Cuts),
        Picture::Retro => (retro::near_peak(data).len() >= retro::MIN_SAMPLES).then_some(Prepared::Retro),
        Picture::Hemisphere => Some(Prepared::Map(hemisphere::measured(data, ti, o.scale, o.range))),
        Picture::Residuals => fits.first().map(|m| Prepared::Map(hemisphere::residuals(data, ti, m))),
    }
}

/// Draws the picture on `root` and writes it out.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, p: &Prepared, data: &Dataset, ti: f64, fits: &[FittedBrdf]) -> Result<()> {
    match p {
        Prepared::Plane => plane::draw(root, data, ti, fits),
        Prepared::Cuts => cuts::draw(root, data, ti, fits.first()),
        Prepared::Retro => retro::draw(root, data, ti, fits),
        Prepared::Map(m) => hemisphere::draw(root, m),
    }?;
    root.present().map_err(err)
}

/// Draws every picture for every incidence angle (residuals only with a
/// fit, the retro peak only where samples lie near it); returns the files
/// written, `{picture}-{θi}.svg` and `.png`.
pub fn render(data: &Dataset, fits: &[FittedBrdf], dir: &Path, options: &Options) -> Result<Vec<PathBuf>> {
    register_font()?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    // The incidences are independent: drawn side by side.
    let per_incidence = data
        .incidence_angles_deg()
        .into_par_iter()
        .map(|ti| render_incidence(data, ti, fits, dir, options))
        .collect::<Result<Vec<_>>>()?;
    Ok(per_incidence.concat())
}

/// Every picture at incidence `ti`.
fn render_incidence(data: &Dataset, ti: f64, fits: &[FittedBrdf], dir: &Path, options: &Options) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let at = data.filter(|o| theta_in(o.theta_i, &[ti]));
    for kind in Picture::ALL {
        let Some(prepared) = prepare(kind, &at, ti, fits, options) else {
            continue;
        };
        let stem = format!("{}-{ti}", kind.name());
        let svg = dir.join(format!("{stem}.svg"));
        draw(&SVGBackend::new(&svg, kind.size()).into_drawing_area(), &prepared, &at, ti, fits)?;
        files.push(svg);
        let png = dir.join(format!("{stem}.png"));
        draw(&BitMapBackend::new(&png, kind.size()).into_drawing_area(), &prepared, &at, ti, fits)?;
        files.push(png);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::Units;
    use crate::uncertainty::SHARED;
    use gonio_brdf::Material;

    #[test]
    fn a_curve_is_cut_where_it_has_no_value() {
        let curve = [(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0), (3.0, 4.0), (4.0, f64::INFINITY)];
        let runs = finite_runs(&curve);
        assert_eq!(runs, vec![&curve[..1], &curve[2..4]]);
        assert!(finite_runs(&[(0.0, f64::NAN)]).is_empty());
    }

    /// A tape at θi = 30° on the default grid plus rings about the light,
    /// each sample with a 2 % σ.
    fn tape() -> Dataset {
        let m = Material::tape();
        let mut directions: Vec<(f64, f64)> = (0..30)
            .flat_map(|o| (-18..18).map(move |p| (3.0 * o as f64, 10.0 * p as f64)))
            .collect();
        directions.extend(
            (1..=8)
                .flat_map(|r| (0..16).map(move |k| (r as f64 * 0.5, k as f64 * 22.5)))
                .map(|(alpha, around)| {
                    // A ring of observation angle α about the light, θi = 30°.
                    let (a, b) = (alpha.to_radians(), around.to_radians());
                    let l = [30f64.to_radians().sin(), 0.0, 30f64.to_radians().cos()];
                    let (e1, e2) = ([l[2], 0.0, -l[0]], [0.0, 1.0, 0.0]);
                    let v: Vec<f64> = (0..3)
                        .map(|i| a.cos() * l[i] + a.sin() * (b.cos() * e1[i] + b.sin() * e2[i]))
                        .collect();
                    (v[2].acos().to_degrees(), v[1].atan2(v[0]).to_degrees())
                }),
        );
        let observations = directions
            .into_iter()
            .map(|(to, dp)| {
                let value = m.eval(&gonio_brdf::Directions::from_degrees(30.0, to, dp));
                Observation {
                    theta_i: 30f64.to_radians(),
                    theta_o: to.to_radians(),
                    dphi: dp.to_radians(),
                    value,
                    sigma: Some(0.02 * value),
                    shared: [0.0; SHARED.len()],
                }
            })
            .collect();
        Dataset::new(Units::Fr, observations)
    }

    fn svg(dir: &Path, stem: &str) -> String {
        std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap()
    }

    /// What a reader needs is in the SVG as text: the colour bars with
    /// their unit, scale and end values, the angle ticks with units, the
    /// axis titles, and error bars where the samples carry σ.
    #[test]
    fn every_picture_carries_its_scales_and_units() {
        let dir = tempfile::tempdir().unwrap();
        let data = tape();
        let mut off = Material::tape();
        off.params[1] = 300.0; // a wider lobe than the data's
        let files = render(&data, &[FittedBrdf::Model(off)], dir.path(), &Options::default()).unwrap();
        assert_eq!(files.len(), 2 * Picture::ALL.len(), "{files:?}");
        let map = svg(dir.path(), "hemisphere-30");
        for text in [
            "f_r (sr⁻¹), log scale",
            "θo = 30°",
            "θo = 60°",
            "Δφ = 0°",
            "90°",
            "270°",
            "retro",
            "mirror",
        ] {
            assert!(map.contains(text), "hemisphere map without `{text}`");
        }
        // The mirror and retro peaks lie above the 99th percentile: the
        // bar's top says its colour holds more.
        assert!(map.contains("≥ "), "the clipped top of the bar is marked");
        assert!(map.matches("10⁻").count() + map.matches("10⁰").count() >= 1, "decade ticks");
        let residuals = svg(dir.path(), "residuals-30");
        assert!(residuals.contains("residual / σ (k = 1)") && residuals.contains("(measured − retro-phong) / σ"));
        let plane = svg(dir.path(), "plane-30");
        for text in ["-60°", "60°", "sr⁻¹", "θo (°), + on the side of the light", "measured (± U, k = 2)"] {
            assert!(plane.contains(text), "plane without `{text}`");
        }
        let cuts = svg(dir.path(), "cuts-30");
        for text in ["θo (°)", "f_r (sr⁻¹)", "Δφ = 0° / 180°", "Δφ = 90° / 270°", "lines: retro-phong"] {
            assert!(
                cuts.contains(text),
                "cuts without `{text}`: {:?}",
                cuts.lines().filter(|l| !l.starts_with('<')).collect::<Vec<_>>()
            );
        }
        let retro = svg(dir.path(), "retro-30");
        assert!(retro.contains("observation angle α (°)") && retro.contains("f_r (sr⁻¹)"));
        // Error bars: plotters draws each as three segments, the whiskers
        // included; a sample without σ draws none.
        let bars = |s: &str| s.matches("<line ").count() + s.matches("<polyline").count();
        let mut bare = data.clone();
        bare.observations.iter_mut().for_each(|o| o.sigma = None);
        let plain = tempfile::tempdir().unwrap();
        render(&bare, &[], plain.path(), &Options::default()).unwrap();
        assert!(
            bars(&retro) > bars(&svg(plain.path(), "retro-30")) + 3 * 16,
            "error bars near the peak"
        );
        assert!(!plain.path().join("residuals-30.svg").exists(), "residuals only with a fit");
    }

    #[test]
    fn a_chosen_range_and_a_linear_scale_reach_the_bar() {
        let dir = tempfile::tempdir().unwrap();
        let o = Options {
            scale: Scale::Linear,
            range: Some((0.05, 2.0)),
        };
        render(&tape(), &[], dir.path(), &o).unwrap();
        let map = svg(dir.path(), "hemisphere-30");
        assert!(map.contains("f_r (sr⁻¹), linear scale"));
        assert!(
            map.contains("≤ 0.050") && map.contains("≥ 2.0"),
            "the range's ends, marked as clipped"
        );
    }

    #[test]
    fn ticks_drop_trailing_zeros() {
        assert_eq!(tick(10.0), "10");
        assert_eq!(tick(-80.0), "-80");
        assert_eq!(tick(0.1), "0.1");
        assert_eq!(tick(2.5e-6), "2.5×10⁻⁶");
        assert_eq!(tick(1e-5), "1×10⁻⁵");
    }
}
