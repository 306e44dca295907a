//! What `gonio fit` and `compare` take: the options a fit sees and how
//! samples are weighed, the files it is drawn as, and the rational
//! function's options; flags only (`fitting.rs` turns them into calls).

use anyhow::Result;
use gonio_analysis::fit::{Units, Weighting};
use gonio_analysis::rational::RationalSpec;
use gonio_brdf::Param;
use std::path::PathBuf;

/// Which samples a fit sees, and how they are weighed.
#[derive(Debug, Clone, clap::Args)]
pub struct FitOptions {
    /// Cosine of the retro lobes: `back` (cos_B) or `view` (cos_R = l·v).
    #[arg(long, value_enum, default_value = "view")]
    pub param: Param,
    /// Fit the retro half-space only (|Δφ| ≤ 90°).
    #[arg(long)]
    pub retro_only: bool,
    /// Fit only these incidence angles (degrees, comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub theta_i: Vec<f64>,
    /// Leave these incidence angles (degrees) out of the fit and report how
    /// well the fit predicts them (cross-validation, as Zhang et al.).
    #[arg(long, value_delimiter = ',')]
    pub holdout_theta_i: Vec<f64>,
    /// Sample weights in the least-squares sum.
    #[arg(long, value_enum, default_value = "uniform")]
    pub weights: Weighting,
    /// Units the residuals are taken in (default: the file's own); for a file
    /// that does not say what its values are (ALTA without #PARAM_OUT), also
    /// what they are.
    #[arg(long, value_enum)]
    pub units: Option<Units>,
    /// Seed of the global search.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Search boxes replacing the defaults, NAME=LO:HI,... (in `compare`,
    /// each model takes the names it has).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, value_name = "NAME=LO:HI")]
    pub bounds: Vec<String>,
    #[command(flatten)]
    pub instrument: super::instrument::InstrumentArgs,
    /// Print one JSON object (errors too: `{"error", "kind"}`).
    #[arg(long)]
    pub json: bool,
}

impl Default for FitOptions {
    /// The command line's defaults, as its attributes give them.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            options: FitOptions,
        }
        <Defaults as clap::Parser>::parse_from(["gonio"]).options
    }
}

#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// Model id (models.md): lambert, retro-phong, abc-retro, abc-retro-per-lobe, beckmann-retro, blinn-retro, lafortune, oren-nayar, five-param,
    /// or `rational` (a rational function through every sample's segment, in the --param retro plane, back or view (light-view),
    /// or in ALTA's view plane, whichever holds with fewer terms).
    #[arg(long)]
    pub model: String,
    #[command(flatten)]
    pub rational: RationalArgs,
    /// Hold a parameter at a value, NAME=V (repeatable).
    #[arg(long)]
    pub fix: Vec<String>,
    /// Write the fit as JSON to this file as well.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the fit as a Disney BRDF Explorer shader (.brdf) as well.
    #[arg(long)]
    pub brdf: Option<PathBuf>,
    /// Write the fit as an RGL .bsdf for Mitsuba 3 and pbrt-v4 as well, at
    /// `gonio export`'s default resolution (a warning on stderr if too coarse).
    #[arg(long)]
    pub bsdf: Option<PathBuf>,
    /// Draw the data and the fit into this directory (PNG and SVG).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub options: FitOptions,
}

#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// Data file: ALTA text (.dat) or calibrated sample CSV (.csv).
    pub file: PathBuf,
    /// Write DIR/report.html: the comparison table, every fit as JSON and
    /// BRDF Explorer shader (DIR/fits), pictures of the best fits (DIR/plots).
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Overwrite a report already in the --report directory.
    #[arg(long, requires = "report")]
    pub force: bool,
    /// The rational function's row (its segments: from the samples' σ,
    /// `joint`, unless --segments says otherwise; where none holds them
    /// all, a note says why).
    #[command(flatten)]
    pub rational: RationalArgs,
    #[command(flatten)]
    pub options: FitOptions,
}

/// The rational function's options, in `fit --model rational` and `compare`.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct RationalArgs {
    /// With the rational function: each sample's segment, `joint` (the default: value ± kσ, k such that the true BRDF lies within
    /// all segments at once with probability 0.95, 4.56 for 10 000 samples), `sigma` (value ± 2σ: the calibrated CSV's k = 2 interval,
    /// ALTA's #VS; with thousands of samples some 5 % of them miss the truth), `abs:WIDTH` (value ± WIDTH, sr⁻¹, of the file's quantity: f_r, or f_r·cosθo as ALTA's tapes store it) or `rel:WIDTH` (value × (1 ± WIDTH)).
    #[arg(long, value_name = "SOURCE")]
    pub segments: Option<String>,
    /// With the rational function: the highest total degree of numerator and denominator tried (8: 330 coefficients).
    #[arg(long, value_name = "D")]
    pub max_degree: Option<usize>,
    /// With the rational function: fit P/Q alone, without the paper's cosθi·cosθo factor (ALTA's
    /// rational_function_legendre; often fewer coefficients for absolute segments).
    #[arg(long)]
    pub no_cosine: bool,
    /// With the rational function: fit a grid of DEG degrees interpolated between the samples at each θi, as
    /// Belcour et al. 2014 did (§6.A), and say how many of the measured samples' segments the function still holds.
    #[arg(long, value_name = "DEG")]
    pub densify: Option<f64>,
}

impl RationalArgs {
    /// Whether any option was given.
    pub fn given(&self) -> bool {
        self.segments.is_some() || self.max_degree.is_some() || self.no_cosine || self.densify.is_some()
    }

    /// The fit these options ask for, in the plane `--param` names.
    pub fn rational_spec(&self, param: Param) -> Result<RationalSpec> {
        Ok(RationalSpec {
            parametrization: param.into(),
            segments: self.segments.as_deref().unwrap_or("joint").parse()?,
            max_degree: self.max_degree.unwrap_or(RationalSpec::MAX_DEGREE),
            cosine: !self.no_cosine,
            densify: self.densify,
        })
    }
}
