//! `twv report`: the study reproduced end to end, and gone past — model and audit, open-loop
//! Lyapunov spectrum and its horizon dependence, phase portraits, tilt recovery, linear
//! analysis with tuned gains and LQR, a stability map, and the study's claims checked.
//!
//! Every section calls the typed API ([`crate::api`]) with typed settings; every sentence that
//! judges a result comes from [`findings`], computed from the results with a stated threshold.
//! The page opens with those findings and with any failed check; [`Report::passed`] is what
//! the binary's exit code follows. Nothing here writes files: [`Report::files`] are written by
//! the caller.

mod findings;
mod html;
mod sections;

use std::time::Instant;

use serde::Serialize;

pub use findings::{
    audit_check, bicycle_finding, equations_claim, hyperchaos_claim, linear_finding, map_finding,
    open_loop_finding, pd_exponents_claim, recovery_claim, recovery_finding, trace_check,
    tune_finding, Check, Claim, Finding, DRIFT_TOLERANCE, TRACE_TOLERANCE,
};
pub use html::{svg_size, Figure, Page, PAGE_PADDING, PAGE_WIDTH};
pub use sections::{BicycleSection, PUSH, PUSH_SPEED};

use crate::api::{LinearReport, PhaseResult, Progress, SimResult, SpectrumResult, TuneReport};
use crate::audit::{AuditReport, AuditSettings};
use crate::error::Result;
use crate::model::ParamSource;
use crate::output::Files;
use crate::sweep::PointResult;

/// What to run. Defaults: the IR's parameters, full horizons.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportSettings {
    /// Parameters of the vehicles (vehicle8 for the study's sections; all three in the audit).
    pub params: ParamSource,
    /// segway7's parameters in the audit, when they differ (its own vehicle file); `None`:
    /// `params`.
    pub segway_params: Option<ParamSource>,
    /// The parameter file's text, shown on the page (the embedded vehicles/paper.toml).
    pub params_text: Option<String>,
    /// Shorter horizons and a coarser map (tests and quick looks).
    pub quick: bool,
    /// The audit's tolerance (normwise relative error of a term). Default 1e-11.
    pub audit_tolerance: f64,
    /// A measured bicycle's parameters with their `[uncertainty]` (front ends embed
    /// vehicles/bicycles/browser.toml): the bicycle section's Monte Carlo. `None`: that part
    /// says it had no measured bicycle.
    pub measured_bicycle: Option<ParamSource>,
}

impl ReportSettings {
    /// The folder a report is written to unless another is named.
    pub const DEFAULT_OUT: &'static str = "report";
}

impl Default for ReportSettings {
    fn default() -> Self {
        Self {
            params: ParamSource::Defaults,
            segway_params: None,
            params_text: None,
            quick: false,
            audit_tolerance: AuditSettings::default().tolerance,
            measured_bicycle: None,
        }
    }
}

/// One horizon of the open-loop spectrum, from both initial bases.
#[derive(Debug, Clone, Serialize)]
pub struct HorizonRow {
    /// T·K [s].
    pub horizon_s: f64,
    /// From the identity basis.
    pub identity: SpectrumResult,
    /// From a random orthonormal basis (seed 1).
    pub random_seed_1: SpectrumResult,
}

/// Everything the report computed, as results.json holds it.
#[derive(Debug, Clone, Serialize)]
pub struct ReportResults {
    /// Whether every check passed.
    pub passed: bool,
    /// The checks.
    pub checks: Vec<Check>,
    /// The findings, in page order.
    pub findings: Vec<Finding>,
    /// The study's claims.
    pub claims: Vec<Claim>,
    /// The model section: description, parameters, the derived terms.
    pub model: sections::ModelSection,
    /// The audits (vehicle8, vehicle7, segway7).
    pub audit: Vec<AuditReport>,
    /// The open-loop spectrum at the study preset.
    pub lyapunov_preset: SpectrumResult,
    /// The same at longer horizons.
    pub lyapunov_horizons: Vec<HorizonRow>,
    /// The phase portraits.
    pub phase: PhaseResult,
    /// Forward and backward tilt recovery.
    pub recovery: Vec<SimResult>,
    /// The linear analysis of the study's PD.
    pub linear: LinearReport,
    /// The tuned gains.
    pub tune: TuneReport,
    /// The stability map's points.
    pub map: Vec<PointResult>,
    /// The closed-loop spectrum under the study's PD.
    pub closed_loop_lyapunov: SpectrumResult,
    /// The Whipple bicycle, unsteered and steered.
    pub bicycle: sections::BicycleSection,
    /// Wall time of the build [s].
    pub wall_time_s: f64,
    /// The CPU and kernel build that wall time was measured on ([`crate::machine::describe`]).
    pub machine: String,
}

/// The report: the page, its files, and the verdict.
pub struct Report {
    /// index.html.
    pub html: String,
    /// Figures (SVG and PNG), data files and results.json, by name under the report folder.
    pub files: Files,
    /// Everything computed.
    pub results: ReportResults,
}

impl Report {
    /// Whether every check passed (the binary exits non-zero otherwise, after writing).
    pub fn passed(&self) -> bool {
        self.results.passed
    }

    /// The checks that failed.
    pub fn failed_checks(&self) -> Vec<&Check> {
        self.results.checks.iter().filter(|c| !c.passed).collect()
    }
}

/// Builds the report (no files written: see [`Report::files`]).
pub fn build(settings: &ReportSettings, progress: &dyn Progress) -> Result<Report> {
    let start = Instant::now();
    progress.start(sections::STEPS as u64, "report sections");
    let result = sections::compute(settings, progress);
    progress.finish();
    let mut results = result?;
    results.wall_time_s = start.elapsed().as_secs_f64();
    results.machine = crate::machine::describe();
    let (html, figures) = sections::page(settings, &results, progress)?;
    let mut files = Files::new();
    for f in &figures {
        files.text(&f.file, f.svg.clone());
        let stem = f.file.strip_suffix(".svg").unwrap_or(&f.file);
        files.entries.push((format!("{stem}.png"), f.png.clone()));
    }
    for (name, text) in sections::data_files(&results) {
        files.text(&name, text);
    }
    files.json("results.json", &results);
    files.text("index.html", html.clone());
    Ok(Report {
        html,
        files,
        results,
    })
}
