//! Tuning the steer loop of a two-wheeler ([`crate::linear::steer`]) to a margin specification
//! at one speed, and along a speed range as a gain schedule: the same convex–concave procedure
//! as the pitch loop's ([`super::tuner`]), with the four gains of the law free in sign, each
//! speed's gains checked independently (closed-loop eigenvalues and the margins on a dense
//! grid).
//!
//! The design stays as close as the spec allows to an LQR design, Q = I on (φ, δ, φ̇, δ̇) and
//! R = `lqr_weight` on the torque: that design stabilises every speed where the loop can be
//! stabilised at all, its SISO return ratio has at least 60° of phase margin and a gain margin
//! of [½, ∞) (so it is usually feasible at once), it makes the slow modes decay (the smallest
//! gains meeting a margin spec would leave a nearly self-stable bicycle to its own slow
//! capsize), and it changes continuously with speed, so the schedule does too.

use nalgebra::{Complex, DMatrix};
use serde::Serialize;

use super::ccp::{Design, Goal};
use super::spec::{Requirement, Spec};
use super::tuner::{design_run, Outcome, Tunable, TuneError, TuneStatus};
use crate::linear::error::LinearError;
use crate::linear::freq::log_grid;
use crate::linear::lqr::lqr;
use crate::linear::margins::{loop_margins, GridOptions};
use crate::linear::steer::{SteerAnalysis, SteerGains, SteerLoop};

/// Settings of the steer tuner. Defaults beside each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SteerTuneOptions {
    /// Bound on each gain as a multiple of its scale (the subproblems stay bounded). 100.
    pub max_gain_factor: f64,
    /// Design-grid density (doubled up to three times when the check fails). 40.
    pub points_per_decade: usize,
    /// Convex subproblems per phase. 60.
    pub max_iterations: usize,
    /// R of the LQR design the gains stay close to (Q = I on the lean-and-steer states):
    /// larger, gentler steering. 0.01.
    pub lqr_weight: f64,
}

impl Default for SteerTuneOptions {
    fn default() -> Self {
        Self {
            max_gain_factor: 100.0,
            points_per_decade: 40,
            max_iterations: 60,
            lqr_weight: 0.01,
        }
    }
}

/// The independent check of steer gains at one speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerCertificate {
    /// The gains checked.
    pub gains: SteerGains,
    /// Closed-loop eigenvalues and the dense-grid margins.
    pub analysis: SteerAnalysis,
    /// Closed loop stable and every requirement met.
    pub meets_spec: bool,
}

/// Checks `gains` on `lp` against `spec`.
pub fn certify_steer(
    lp: &SteerLoop,
    gains: &SteerGains,
    spec: &Spec,
) -> Result<SteerCertificate, LinearError> {
    let analysis = lp.analyse(gains)?;
    let meets_spec = analysis.closed_loop.stable && spec.met_by(&analysis.margins);
    Ok(SteerCertificate {
        gains: *gains,
        analysis,
        meets_spec,
    })
}

/// The tuner's answer at one speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerTune {
    /// The speed [m/s].
    pub speed: f64,
    /// How it ended.
    pub status: TuneStatus,
    /// The check of the returned gains (for `Infeasible`, the best gains found; `None` if no
    /// stabilising gains were found).
    pub certificate: Option<SteerCertificate>,
    /// 1 when met; for `Infeasible`, the largest fraction of the spec met.
    pub best_fraction: f64,
    /// Convex subproblems of the final phase 2.
    pub iterations: usize,
}

impl SteerTune {
    /// Verified gains that meet the spec.
    pub fn met(&self) -> bool {
        matches!(self.status, TuneStatus::Solved | TuneStatus::IterationLimit)
            && self.certificate.as_ref().is_some_and(|c| c.meets_spec)
    }
}

/// The steer loop as a [`Tunable`] loop.
struct SteerDesign<'a> {
    lp: &'a SteerLoop,
    options: &'a SteerTuneOptions,
}

impl SteerDesign<'_> {
    /// ω_ref, the largest open-loop pole magnitude (1 rad/s if all are 0).
    fn reference_frequency(&self) -> Result<f64, LinearError> {
        let w = self
            .lp
            .open_loop_eigenvalues()?
            .iter()
            .map(|p| p.norm())
            .fold(0.0, f64::max);
        Ok(if w > 0.0 { w } else { 1.0 })
    }

    /// Disk margin α of a stable loop on a coarse grid, `None` if unstable.
    fn coarse_alpha(&self, g: &SteerGains) -> Result<Option<f64>, LinearError> {
        let closed = self.lp.closed_loop(g)?;
        if !closed.stable {
            return Ok(None);
        }
        let mut grid = GridOptions::around(&self.lp.scales(&closed)?);
        grid.points_per_decade = 20;
        grid.refine_floor = 0.1;
        let l0 = |w: f64| self.lp.response(g, w);
        let m = loop_margins(&l0, 0.0, true, &grid);
        Ok(m.stable.then_some(m.disk.alpha))
    }
}

impl Tunable for SteerDesign<'_> {
    type Gains = SteerGains;
    type Certificate = SteerCertificate;

    /// A log grid of [1e-3, 1e3] ω_ref (and DC where the plant has no pole there); each gain
    /// scaled by 1/|φ_j(jω_ref)| and bounded by ± `max_gain_factor` times its scale.
    fn design(&self, ppd: usize) -> Result<Design, TuneError> {
        let w_ref = self.reference_frequency()?;
        let at_ref = [1.0, 2.0, 0.5]
            .iter()
            .find_map(|k| {
                self.lp
                    .basis(k * w_ref)
                    .filter(|b| b.iter().all(|v| v.norm() > 0.0))
            })
            .ok_or(TuneError::Option {
                what: "model",
                why: "the steer torque does not reach every lean-and-steer state at the \
                      reference frequency",
            })?;
        let scale: Vec<f64> = at_ref.iter().map(|b| 1.0 / b.norm()).collect();
        let mut grid = log_grid(1e-3 * w_ref, 1e3 * w_ref, ppd);
        grid.insert(0, 0.0);
        let basis: Vec<Vec<Complex<f64>>> = grid
            .iter()
            .filter_map(|&w| self.lp.basis(w).map(|b| b.to_vec()))
            .collect();
        let bound: Vec<f64> = scale
            .iter()
            .map(|s| s * self.options.max_gain_factor)
            .collect();
        let lower: Vec<f64> = bound.iter().map(|b| -b).collect();
        Ok(Design::from_basis(basis, scale, &lower, &bound))
    }

    fn gains(&self, design: &Design, x: &[f64]) -> SteerGains {
        let k = design.values(x);
        SteerGains::from_row([k[0], k[1], k[2], k[3]])
    }

    fn certify(
        &self,
        g: &SteerGains,
        spec: &Spec,
    ) -> Result<(SteerCertificate, bool), LinearError> {
        let cert = certify_steer(self.lp, g, spec)?;
        let meets = cert.meets_spec;
        Ok((cert, meets))
    }

    fn certified(c: &SteerCertificate) -> SteerGains {
        c.gains
    }

    /// `x0` if it stabilises; else the LQR design with Q = I, R = ρ over ρ ∈ {10⁻⁴ … 10⁴}
    /// (each a stabilising full-state law, which is this loop's family) inside the bounds with
    /// the largest coarse disk margin.
    fn stabilising_start(
        &self,
        design: &Design,
        x0: Vec<f64>,
    ) -> Result<Option<Vec<f64>>, LinearError> {
        if self.coarse_alpha(&self.gains(design, &x0))?.is_some() {
            return Ok(Some(x0));
        }
        let mut best: Option<(f64, Vec<f64>)> = None;
        for e in -4..=4 {
            let Some(k) = lqr_gains(self.lp, 10f64.powi(e)) else {
                continue;
            };
            let x = design.scaled_values(&k.row());
            let inside = x
                .iter()
                .zip(design.lower.iter().zip(&design.upper))
                .all(|(v, (l, u))| v >= l && v <= u);
            if !inside {
                continue;
            }
            if let Some(alpha) = self.coarse_alpha(&self.gains(design, &x))? {
                if !best.as_ref().is_some_and(|b| alpha <= b.0) {
                    best = Some((alpha, x));
                }
            }
        }
        Ok(best.map(|b| b.1))
    }
}

/// Checks the spec for what the steer loop can design for: disk and sensitivity margins (the
/// effort bound `force<=` is the pitch loop's).
pub fn check_spec(spec: &Spec) -> Result<(), TuneError> {
    if spec
        .requirements
        .iter()
        .any(|r| matches!(r, Requirement::PeakForce { .. }))
    {
        return Err(TuneError::Option {
            what: "spec",
            why: "force<= bounds the pitch loop's force; the steer loop takes dpm, dgm and ms",
        });
    }
    Ok(())
}

/// Checks the options; the error names the first bad one.
pub fn validate(options: &SteerTuneOptions) -> Result<(), TuneError> {
    if !(options.max_gain_factor.is_finite() && options.max_gain_factor > 0.0) {
        return Err(TuneError::Option {
            what: "max_gain_factor",
            why: "must be finite and > 0",
        });
    }
    if !(2..=super::tuner::MAX_POINTS_PER_DECADE).contains(&options.points_per_decade) {
        return Err(TuneError::Option {
            what: "points_per_decade",
            why: "must be between 2 and 10000",
        });
    }
    if !(1..=super::tuner::MAX_ITERATIONS).contains(&options.max_iterations) {
        return Err(TuneError::Option {
            what: "max_iterations",
            why: "must be between 1 and 10000",
        });
    }
    if !(options.lqr_weight.is_finite() && options.lqr_weight > 0.0) {
        return Err(TuneError::Option {
            what: "lqr_weight",
            why: "must be finite and > 0",
        });
    }
    Ok(())
}

/// The LQR gains of the steer law at this speed, Q = I, R = `r` (`None` where the Riccati
/// equation has no stabilising solution: the torque cannot stabilise the loop).
pub fn lqr_gains(lp: &SteerLoop, r: f64) -> Option<SteerGains> {
    let b = DMatrix::from_column_slice(4, 1, lp.b().as_slice());
    let design = lqr(
        lp.a(),
        &b,
        &DMatrix::identity(4, 4),
        &DMatrix::from_element(1, 1, r),
    )
    .ok()?;
    let stable = design.spectral_abscissa < 0.0; // false for NaN too
    if design.status != crate::linear::CareStatus::Solved || !stable {
        return None;
    }
    // u = −K x in LQR's convention; the steer law is T = +K x.
    let k: Vec<f64> = design.k.iter().map(|v| -v).collect();
    Some(SteerGains::from_row([k[0], k[1], k[2], k[3]]))
}

/// Tunes the steer loop `lp` to `spec`: the gains closest (scaled least squares) to the LQR
/// design of `options.lqr_weight` that meet it, started from that design.
pub fn tune_steer(
    lp: &SteerLoop,
    spec: &Spec,
    options: &SteerTuneOptions,
    stop: &dyn Fn() -> bool,
) -> Result<SteerTune, TuneError> {
    validate(options)?;
    check_spec(spec)?;
    let steer = SteerDesign { lp, options };
    let reference = lqr_gains(lp, options.lqr_weight);
    // Without an LQR design (the torque cannot stabilise the loop), start from no steering
    // and let the search for a stabilising start decide.
    let x0 = |d: &Design| d.scaled_values(&reference.unwrap_or_default().row());
    let goal = |d: &Design| match reference {
        Some(k) => Goal::Target(d.scaled_values(&k.row())),
        None => Goal::MinGain,
    };
    let outcome: Outcome<SteerCertificate> = design_run(
        &steer,
        spec,
        &goal,
        &x0,
        options.points_per_decade,
        options.max_iterations,
        stop,
    )?;
    Ok(SteerTune {
        speed: lp.speed(),
        status: outcome.status,
        certificate: outcome.certificate,
        best_fraction: outcome.best_fraction,
        iterations: outcome.iterations,
    })
}
