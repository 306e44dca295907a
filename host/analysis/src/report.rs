//! `report.html`: what a scan or a data file gave, to read offline in any
//! browser: the facts of the run, the model comparison table (Spieringhs
//! Table 6 style: coefficients, RMSE, NRMSE, NCC), every fit as JSON and as a
//! BRDF Explorer shader, and the pictures with the best fits drawn over the
//! data. Everything it links is written beside it, by relative path.

use crate::calibration::IncidenceBudget;
use crate::coefficients::{self, Estimate, Fitted, Kind, Provenance, Source, Support};
use crate::fit::compared::{best_first, ComparedFit};
use crate::fit::file::{self as fit_file, FittedBrdf};
use crate::fit::goodness::{Adequacy, Goodness, ADEQUATE_P};
use crate::fit::{Dataset, Metrics};
use crate::formats::{export, rgl};
use crate::plot;
use crate::render;
use crate::rounding;
use anyhow::{Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// How many of the best fits are drawn over the data (more curves than this
/// hide each other).
const DRAWN: usize = 3;

/// What a report shows.
pub struct Report<'a> {
    pub title: String,
    /// Facts shown above the table: `(what, value)`.
    pub facts: Vec<(String, String)>,
    pub data: &'a Dataset,
    pub fits: &'a [ComparedFit],
    /// Fits the comparison tried and could not make, and why (the rational
    /// function when no function of the allowed degree holds every segment).
    pub unfitted: &'a [String],
    /// Metrics on held-out samples, one per fit, if the comparison held any out.
    pub holdout: &'a [Option<Metrics>],
    /// The calibration's budget per incidence angle, when the data were calibrated here.
    pub budget: &'a [IncidenceBudget],
}

/// Every fit with what weighs it against the others.
fn fitted(fits: &[ComparedFit]) -> Vec<Fitted> {
    fits.iter().map(ComparedFit::fitted).collect()
}

/// One table cell: the value ± u, extrapolated ones marked, values the
/// data cannot support named with their reason.
fn coefficient_cell(e: &Estimate) -> String {
    let provenance = e.basis.as_ref().map(|b| b.provenance);
    let title = e.basis.as_ref().map_or(String::new(), |b| escape(&b.why));
    let text = format!("<span class=\"n\">{}</span>", rounding::with_uncertainty(e.value, e.u));
    match provenance {
        Some(Provenance::Extrapolated) => format!(
            "<td class=\"ex\" title=\"{title}\">{text}<br><small>extrapolated ({}, models ±{})</small></td>",
            e.model.unwrap_or("model"),
            rounding::significant(e.u_model.unwrap_or(0.0), 2)
        ),
        Some(Provenance::NotMeasured) => format!("<td class=\"nm\" title=\"{title}\">—<br><small>not measured</small></td>"),
        Some(p) => format!("<td title=\"{title}\">{text}<br><small>{}</small></td>", p.name()),
        None => format!("<td>{text}</td>"),
    }
}

/// The report's first word on the models: whether any is consistent with
/// the data within their uncertainty, and so whether any may carry a
/// coefficient where the data end.
fn adequacy_paragraph(fits: &[ComparedFit]) -> String {
    let judged: Vec<(&ComparedFit, &Goodness)> = fits.iter().filter_map(|f| Some((f, f.goodness()?))).collect();
    if judged.is_empty() {
        return "<p><b>Adequacy cannot be judged</b>: the data carry no uncertainties, so no residual can be weighed \
                against what the measurement allows. The table ranks the models by RMSE only, and the coefficients rest \
                on the data alone: where they do not hold a geometry, no value is given.</p>\n"
            .into();
    }
    let adequate: Vec<&str> = judged
        .iter()
        .filter(|(_, g)| Adequacy::of(Some(g)) == Adequacy::Adequate)
        .map(|(f, _)| f.name())
        .collect();
    let level = format!("χ² test at the {} % level", rounding::significant(100.0 * ADEQUATE_P, 1));
    if adequate.is_empty() {
        let (f, g) = judged.iter().max_by(|a, b| a.1.closer(b.1)).copied().expect("judged is not empty");
        return format!(
            "<p><b>No model is consistent with the data</b> within their uncertainty ({level}): the closest, {}, has \
             reduced χ² {} over {} degrees of freedom. Its parameters describe the data's shape, not the material; \
             the coefficients rest on the data alone, and where they do not hold a geometry no value is given.</p>\n",
            f.name(),
            rounding::significant(g.reduced_chi2, 3),
            g.dof
        );
    }
    format!(
        "<p><b>Consistent with the data</b> within their uncertainty ({level}): {}. Only these carry coefficients \
         where the data end, within the data's own spacing.</p>\n",
        escape(&adequate.join(", "))
    )
}

/// R_A (ASTM E810 set, ε = 0: the BRDF is isotropic) and R_L (EN 1436):
/// from the data where they hold the geometry, from the best fit beyond it
/// (marked, with the adequate models' spread in its uncertainty), and the
/// picture of R_A against α per β.
fn coefficients_section(fits: &[ComparedFit], support: Support, dir: &Path) -> Result<String> {
    let all = fitted(fits);
    let adequate: Vec<Fitted> = all.iter().filter(|f| f.is_adequate()).cloned().collect();
    let carrier = coefficients::best(&adequate).map_or("none: no model is adequate, so such values are not given", |(_, m)| m.model.name());
    let models: Vec<&ComparedFit> = fits.iter().filter(|f| matches!(f, ComparedFit::Model(_))).collect();
    let instrument = support.instrument;
    let source = Source::measured(all, support)?;
    let values = coefficients::compute(&source, &coefficients::report_requests())?;
    let mut html = format!(
        "<h2>Coefficients of retroreflection</h2>\n<p>Each value says what it rests on. <b>measured</b>: a sample of \
         this scan at the geometry, carried from {instrument} to the standard's apertures with the samples' own \
         curvature; <b>interpolated</b>: between samples on every side within the standard's aperture; \
         <b>extrapolated</b> (shaded): no sample there but within the data's own spacing (an entrance angle between \
         measured ones, or beyond them by at most their finest step): the best adequate model by AIC ({carrier}) carries \
         it, scaled to the data at the nearest measured incidences, and its uncertainty holds half the spread of every \
         adequate model; <b>not measured</b>: farther from the data than their spacing, or no model is adequate to carry \
         it: no value (the reason and the scan that would measure it are in the cell's tooltip and in \
         <code>gonio coefficients --json</code>; <code>--extrapolate</code> computes it all the same). The rational \
         function, held by its segments only where there are samples, carries none. ± the standard uncertainty (k = \
         1{}). Spectral values at {wavelength}, <b>not photometric</b>. Definitions: docs/retroreflection.md.</p>\n\
         <table>\n<tr><th class=\"l\">R_A (cd·lx⁻¹·m⁻²)</th>",
        if models.iter().all(|f| matches!(f, ComparedFit::Model(m) if m.covariance.is_some())) {
            ": the samples' budgets, the fit's covariance with the plate and the stage zeros"
        } else {
            "; a fit without covariance adds no parameter term"
        },
        instrument = instrument.apertures_text(),
        wavelength = instrument.wavelength_text(),
    );
    for a in coefficients::ASTM_ALPHAS {
        let _ = write!(html, "<th>α = {a}°</th>");
    }
    html.push_str("</tr>\n");
    for b in coefficients::ASTM_BETAS {
        let _ = write!(html, "<tr><th class=\"l\">β = {b}°</th>");
        for c in values
            .iter()
            .filter(|c| c.request.kind == Kind::Ra && c.request.geometry.beta1_deg == b)
        {
            html.push_str(&coefficient_cell(&c.estimate));
        }
        html.push_str("</tr>\n");
    }
    html.push_str("</table>\n");
    if let Some(rl) = values.iter().find(|c| c.request.kind == Kind::Rl) {
        let _ = writeln!(
            html,
            "<p>R_L at the 30 m geometry (EN 1436: entrance {}°, observation {}°, mcd·m⁻²·lx⁻¹):</p>\n<table><tr>{}</tr></table>",
            coefficients::EN1436_ENTRANCE_DEG,
            coefficients::EN1436_OBSERVATION_DEG,
            coefficient_cell(&rl.estimate)
        );
    }
    let picture = plot::coefficients::render(&source, &dir.join("plots"))?;
    let _ = writeln!(
        html,
        "<figure><img src=\"plots/{}\" alt=\"R_A against α\"><figcaption>R_A against the observation angle α per entrance \
         angle β: solid where measured or interpolated, dashed where extrapolated (k = 2 band shaded).</figcaption></figure>",
        picture.file_name().and_then(|n| n.to_str()).unwrap_or_default()
    );
    Ok(html)
}

/// χ²/dof, p and the verdict of a fit: empty with a reason where the data
/// carry no uncertainties.
fn goodness_cells(g: Option<&Goodness>) -> String {
    match g {
        Some(g) => format!(
            "<td>{}</td><td>{}</td><td class=\"l\">{}</td>",
            rounding::significant(g.reduced_chi2, 3),
            rounding::significant(g.p_value, 2),
            Adequacy::of(Some(g)).name()
        ),
        None => "<td></td><td></td><td class=\"l\">not judged (no uncertainties)</td>".into(),
    }
}

/// The largest components of the calibration's budget per incidence angle.
fn budget_section(budget: &[IncidenceBudget]) -> String {
    let mut html = String::from(
        "<h2>Uncertainty budget</h2>\n<p>Median over the usable samples of each incidence angle, relative to the value \
         (k = 1); every sample's components are in calibrated.csv.</p>\n<table>\n\
         <tr><th>θi</th><th>samples</th><th>combined</th><th class=\"l\">largest components</th></tr>\n",
    );
    for b in budget {
        let top: Vec<String> = b
            .components
            .iter()
            .take(4)
            .map(|(n, u)| format!("{n} {:.3} %", 100.0 * u))
            .collect();
        let _ = writeln!(
            html,
            "<tr><td>{}°</td><td>{}</td><td>{:.3} %</td><td class=\"l\">{}</td></tr>",
            b.theta_i_deg,
            b.samples,
            100.0 * b.combined,
            escape(&top.join(", "))
        );
    }
    html.push_str("</table>\n");
    html
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `value ± stderr` of each parameter; what the rational function is.
fn params_cell(f: &ComparedFit) -> String {
    match f {
        ComparedFit::Model(f) => f
            .material
            .model
            .param_names()
            .iter()
            .enumerate()
            .map(|(k, n)| format!("<span class=\"n\">{n} = {}</span>", f.parameter_text(k)))
            .collect::<Vec<_>>()
            .join("<br>"),
        ComparedFit::Rational { fit, .. } => escape(&format!(
            "degree {} in the {} plane{} ({} over {} coefficients), through every segment {}; L∞ {}",
            fit.function.degree,
            fit.function.coordinates.name(),
            if fit.function.cosine { ", times cosθi·cosθo" } else { "" },
            fit.function.numerator.len(),
            fit.function.denominator.len(),
            fit.segments_text(),
            rounding::significant(fit.linf, 4)
        )),
    }
}

/// Removes the fit files an earlier report wrote into `fits_dir` (a report
/// written again with `--force`): a fit this one does not make (the
/// rational function, fitted then and not now) must not be left beside
/// it as if it were. Only files a report names are touched.
fn remove_earlier_fits(fits_dir: &Path) -> Result<()> {
    let names: Vec<&str> = gonio_brdf::ModelId::ALL
        .iter()
        .map(|m| m.name())
        .chain([crate::rational::file::MODEL])
        .collect();
    for name in names {
        for ext in ["json", "brdf", "bsdf"] {
            let path = fits_dir.join(format!("{name}.{ext}"));
            if path.is_file() {
                std::fs::remove_file(&path).with_context(|| format!("cannot remove {}", path.display()))?;
            }
        }
    }
    Ok(())
}

/// The best fit as an RGL `.bsdf` in `fits/`, and Mitsuba 3's pictures of
/// it beside our integration of the same scenes (`render.rs`) where Mitsuba
/// is installed; without it the section says so and keeps the file.
fn renders_section(best: &ComparedFit, fits_dir: &Path, plots_dir: &Path) -> Result<String> {
    let name = best.name();
    let brdf = best.brdf();
    let eval = |d: &gonio_brdf::Directions| brdf.eval(d);
    let mut html = String::from("<h2>Rendered</h2>\n");
    let options = rgl::Options::default();
    let description = rgl::description(&format!("a report's best fit, {name}"), options.spectrum);
    let table = match rgl::Table::new(&eval, &description, &options) {
        Ok(t) => t,
        Err(e) => {
            let _ = writeln!(
                html,
                "<p>The best fit, {name}, cannot be tabulated for a renderer: {}</p>",
                escape(&e.to_string())
            );
            return Ok(html);
        }
    };
    let file = fits_dir.join(format!("{name}.bsdf"));
    std::fs::write(&file, table.bytes()).with_context(|| format!("cannot write {}", file.display()))?;
    let acc = rgl::accuracy(&table, &eval, rgl::CHECK_PAIRS, rgl::CHECK_LOBE_DEG.to_radians());
    let _ = writeln!(
        html,
        "<p>The best fit, {name}, as the RGL file <a href=\"fits/{name}.bsdf\">fits/{name}.bsdf</a> that Mitsuba 3 and \
         pbrt-v4 render (docs/render.md). Read back as they read it: median error {:.2} %, 95th percentile {:.2} %, \
         retro peak {:.2} %{}.</p>",
        100.0 * acc.median,
        100.0 * acc.p95,
        100.0 * acc.retro_peak,
        if acc.within_tolerance() {
            ""
        } else {
            ": <b>outside the tolerance</b> (median 2 %, 95th percentile 10 %, retro peak 5 %); `gonio export` with a finer grid holds it closer"
        }
    );
    std::fs::create_dir_all(plots_dir).with_context(|| format!("creating {}", plots_dir.display()))?;
    let scenes = render::scenes();
    for s in &scenes {
        let png = plots_dir.join(format!("{}.png", s.name));
        if png.is_file() {
            std::fs::remove_file(&png).with_context(|| format!("cannot remove {}", png.display()))?;
        }
    }
    match render::with_mitsuba(&file, &scenes, Some(plots_dir)) {
        Ok(drawn) => {
            html.push_str("<p>A plane of the material under an orthographic camera 30° from its normal; both pictures at one exposure.</p>\n<div class=\"row\">\n");
            for (s, m) in scenes.iter().zip(&drawn.means) {
                let _ = writeln!(
                    html,
                    "<figure><img src=\"plots/{n}.png\" alt=\"{n}\"><figcaption>{}: mean radiance {} (Mitsuba {}), {} \
                     by our integration of the model</figcaption></figure>",
                    escape(s.caption),
                    rounding::significant(*m, 4),
                    escape(&drawn.mitsuba),
                    rounding::significant(s.mean_radiance(&eval), 4),
                    n = s.name
                );
            }
            html.push_str("</div>\n");
        }
        Err(e) => {
            let _ = writeln!(html, "<p>Not drawn: {}.</p>", escape(&format!("{e:#}")));
        }
    }
    Ok(html)
}

/// Fits sorted best first (RMSE on the fitted samples).
fn ranked(fits: &[ComparedFit]) -> Vec<usize> {
    best_first(&fits.iter().map(|f| f.metrics().rmse).collect::<Vec<_>>())
}

/// Writes `dir/report.html` with `dir/fits/` and `dir/plots/`; returns the
/// report's path.
pub fn write(dir: &Path, r: &Report) -> Result<PathBuf> {
    let fits_dir = dir.join("fits");
    std::fs::create_dir_all(&fits_dir).with_context(|| format!("creating {}", fits_dir.display()))?;
    remove_earlier_fits(&fits_dir)?;
    let order = ranked(r.fits);
    // What the data hold near the laser: kept in every fit file, and what
    // the coefficients rest on.
    let support = Support::of(r.data)?;
    let mut html = head(r);
    html.push_str(&models_section(r, &order, &fits_dir, &support)?);
    if !r.fits.is_empty() {
        html.push_str(&coefficients_section(r.fits, support, dir)?);
    }
    if !r.budget.is_empty() {
        html.push_str(&budget_section(r.budget));
    }
    // The renderer (its tabulation, then Mitsuba's process) and the
    // pictures are independent: drawn side by side.
    let plots = dir.join("plots");
    let (renders, pictures) = rayon::join(
        || {
            order
                .first()
                .map(|&best| renders_section(&r.fits[best], &fits_dir, &plots))
                .transpose()
        },
        || pictures_section(r, &order, &plots),
    );
    html.push_str(&renders?.unwrap_or_default());
    html.push_str(&pictures?);
    let _ = writeln!(html, "<p><small>gonio {}</small></p>\n</body>\n</html>", env!("CARGO_PKG_VERSION"));
    let path = dir.join("report.html");
    std::fs::write(&path, html).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// The page's head, its title, the adequacy of the fits, and the facts of
/// the data (what measured them, in which units).
fn head(r: &Report) -> String {
    let mut html = String::new();
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{t}</title>\n<style>\n\
         body {{ font-family: sans-serif; margin: 2em; max-width: 75em; }}\n\
         table {{ border-collapse: collapse; }}\n\
         td, th {{ border: 1px solid #bbb; padding: 0.3em 0.6em; text-align: right; vertical-align: top; }}\n\
         td.l, th.l {{ text-align: left; }}\n\
         span.n {{ white-space: nowrap; }}\n\
         tr.best {{ background: #eef6ee; }}\n\
         td.ex {{ background: #f3eee2; font-style: italic; }}\n\
         td.nm {{ color: #777; }}\n\
         div.row {{ display: flex; gap: 0.8em; overflow-x: auto; }}\n\
         figure {{ margin: 0.3em 0; flex: none; }}\n\
         figcaption {{ max-width: 40em; }}\n\
         </style>\n</head>\n<body>\n<h1>{t}</h1>\n{adequacy}<table>\n",
        t = escape(&r.title),
        adequacy = adequacy_paragraph(r.fits)
    );
    for (k, v) in &r.facts {
        let _ = writeln!(
            html,
            "<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>",
            escape(k),
            escape(v)
        );
    }
    let _ = writeln!(
        html,
        "<tr><th class=\"l\">samples fitted</th><td class=\"l\">{} (residuals in {})</td></tr>\n\
         <tr><th class=\"l\">measured by</th><td class=\"l\">{}, at {}</td></tr>\n</table>",
        r.data.observations.len(),
        r.data.units.label(),
        escape(&r.data.instrument.apertures_text()),
        escape(&r.data.instrument.wavelength_text())
    );
    html
}

/// The table of models in `order`, each fit written to `fits_dir` as JSON
/// (with the data's `support`) and as a BRDF Explorer shader.
fn models_section(r: &Report, order: &[usize], fits_dir: &Path, support: &Support) -> Result<String> {
    let holdout = r.holdout.iter().any(Option::is_some);
    let mut html = String::from("<h2>Models</h2>\n<p>Best first by RMSE. Each model is fitted without a starting point (global search, then bounded Levenberg–Marquardt); the rational function (Belcour et al. 2014 §5.B) is the least-norm one of the fewest terms that passes through every sample's segment.</p>\n<table>\n<tr><th class=\"l\">model</th><th>coeffs</th><th>RMSE (sr⁻¹)</th><th>NRMSE</th><th>NCC</th><th>χ²/dof</th><th>p</th><th class=\"l\">adequacy</th>");
    if holdout {
        html.push_str("<th>held-out NRMSE</th><th>held-out NCC</th>");
    }
    html.push_str("<th>s</th><th class=\"l\">parameters</th><th class=\"l\">files</th></tr>\n");
    for (rank, &i) in order.iter().enumerate() {
        let f = &r.fits[i];
        let (name, m) = (f.name(), f.metrics());
        let held_out = r.holdout.get(i).and_then(Option::as_ref);
        fit_file::write_with_support(&fits_dir.join(format!("{name}.json")), &f.to_json(r.data.units, held_out), support)?;
        let comment = format!("{}: RMSE {:.4e} sr^-1, NCC {:.5}", r.title, m.rmse, m.ncc);
        export::write_brdf(&f.brdf(), &comment, &fits_dir.join(format!("{name}.brdf")))?;
        let _ = write!(
            html,
            "<tr{}><td class=\"l\">{name}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>{}",
            if rank < DRAWN { " class=\"best\"" } else { "" },
            f.coefficients(),
            rounding::significant(m.rmse, 4),
            rounding::significant(m.nrmse, 4),
            rounding::figure(m.ncc, 5),
            goodness_cells(f.goodness())
        );
        match held_out {
            Some(h) => {
                let _ = write!(
                    html,
                    "<td>{}</td><td>{}</td>",
                    rounding::significant(h.nrmse, 4),
                    rounding::figure(h.ncc, 5)
                );
            }
            None if holdout => html.push_str("<td></td><td></td>"),
            None => {}
        }
        let _ = writeln!(
            html,
            "<td>{:.2}</td><td class=\"l\">{}</td><td class=\"l\"><a href=\"fits/{name}.json\">JSON</a> · \
             <a href=\"fits/{name}.brdf\">BRDF Explorer</a></td></tr>",
            f.seconds(),
            params_cell(f)
        );
    }
    html.push_str("</table>\n");
    for why in r.unfitted {
        let _ = writeln!(html, "<p>Not fitted: {}</p>", escape(why));
    }
    Ok(html)
}

/// The best fits drawn over the data into `plots_dir`, a row of pictures
/// per incidence.
fn pictures_section(r: &Report, order: &[usize], plots_dir: &Path) -> Result<String> {
    let drawn: Vec<FittedBrdf> = order.iter().take(DRAWN).map(|&i| r.fits[i].brdf()).collect();
    let names: Vec<&str> = drawn.iter().map(FittedBrdf::name).collect();
    let files = plot::render(r.data, &drawn, plots_dir, &plot::Options::default())?;
    let mut html = String::new();
    let _ = writeln!(
        html,
        "<h2>Pictures</h2>\n<p>Drawn: {}. One row per incidence angle (scroll it sideways); click a picture for \
         its SVG. Error bars and U: the expanded uncertainty (k = {}) of each sample's budget.</p>",
        escape(&names.join(", ")),
        crate::uncertainty::K_COVERAGE
    );
    for ti in r.data.incidence_angles_deg() {
        let _ = writeln!(html, "<h3>θi = {ti}°</h3>\n<div class=\"row\">");
        for kind in plot::Picture::ALL {
            let stem = format!("{}-{ti}", kind.name());
            if !files.iter().any(|p| p.file_stem().and_then(|s| s.to_str()) == Some(stem.as_str())) {
                continue;
            }
            let _ = writeln!(
                html,
                "<figure><a href=\"plots/{stem}.svg\"><img src=\"plots/{stem}.png\" alt=\"{stem}\"></a><figcaption>{}</figcaption></figure>",
                escape(kind.describe())
            );
        }
        html.push_str("</div>\n");
    }
    Ok(html)
}
