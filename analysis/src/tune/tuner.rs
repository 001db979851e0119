//! `twv tune`: fit PD/PID gains to a margin specification with the convex–concave procedure
//! of [`super::ccp`], verify them independently ([`super::certificate`]), and when the
//! specification cannot be met say so, with the best margin found — never a silently relaxed
//! spec.
//!
//! The design grid is coarser than the verification grid, so the design aims a little past the
//! spec (0.1 %, then 1 %, 10 %, with a denser grid each time) until the independent check
//! passes. "Infeasible" means phase 1 (slack minimisation) stalled from the start gains; the
//! procedure is local, so it is an honest "no gains found", and the best achievable margin is
//! the largest fraction t of the spec (bisection on t, each step warm-started) whose gains
//! pass the independent check.

use super::ccp::{phase1, phase2, Design, Goal, Objective, Phase1, Phase2End};
use super::certificate::{certify, Certificate};
use super::spec::Spec;
use crate::linear::disk::Disk;
use crate::linear::error::LinearError;
use crate::linear::margins::{loop_margins, GridOptions};
use crate::linear::pitch::{LoopOptions, PidGains, PitchLoop};

/// How the tuning ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TuneStatus {
    /// Gains found and independently verified.
    Solved,
    /// Verified gains, but the objective was still improving when the budget ran out.
    IterationLimit,
    /// No gains meeting the spec were found; see `best_fraction` and the certificate of the
    /// best gains.
    Infeasible,
    /// Gains met the spec on the design grid but never passed the independent check.
    Unverified,
}

/// Tuning settings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TuneOptions {
    /// Tune a PID (Ki free) instead of a PD.
    pub pid: bool,
    /// What to optimise; `None`: Target if `target` is given, else MinGain (PD) or
    /// MaxIntegral (PID).
    pub objective: Option<Objective>,
    /// Gains to stay close to (`--target`).
    pub target: Option<PidGains>,
    /// Start gains (default: the target, else Kp = s_p, Kd = s_d with the plant's gain scales).
    pub start: Option<PidGains>,
    /// Actuator lag and delay in the loop.
    pub loop_options: LoopOptions,
    /// Upper bound of each gain as a multiple of its scale (keeps the subproblems bounded).
    pub max_gain_factor: f64,
    /// Design-grid density.
    pub points_per_decade: usize,
    /// Convex subproblems per phase.
    pub max_iterations: usize,
    /// The tilt [rad] of the certificate's recovery, on which a `force<=` bound is imposed as
    /// Kp·tilt ≤ F (the force at the start of the recovery).
    pub effort_tilt: f64,
}

impl Default for TuneOptions {
    fn default() -> Self {
        Self {
            pid: false,
            objective: None,
            target: None,
            start: None,
            loop_options: LoopOptions::default(),
            max_gain_factor: 100.0,
            points_per_decade: 40,
            max_iterations: 60,
            effort_tilt: 0.1,
        }
    }
}

impl TuneResult {
    /// Whether the tuning succeeded: verified gains that meet every margin requirement (the
    /// effort bound, if any, is checked on the nonlinear model by the caller).
    pub fn met(&self) -> bool {
        matches!(self.status, TuneStatus::Solved | TuneStatus::IterationLimit)
            && self.certificate.as_ref().is_some_and(|c| c.meets_spec)
    }
}

/// The tuner's answer.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TuneResult {
    /// How it ended.
    pub status: TuneStatus,
    /// The spec asked for.
    pub spec: Spec,
    /// The independent check of the returned gains (for `Infeasible`, the best gains found;
    /// `None` if not even a stabilising gain was found).
    pub certificate: Option<Certificate>,
    /// 1 when solved; for `Infeasible`, the largest fraction t of the spec met (see
    /// [`Spec::scaled`]).
    pub best_fraction: f64,
    /// Convex subproblems solved in the final phase 2.
    pub iterations: usize,
}

/// Bad tuner input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TuneError {
    /// Bad loop data (gains, lag, delay, model).
    #[error(transparent)]
    Linear(#[from] LinearError),
    /// A setting out of range.
    #[error("tuner option {what} is invalid: {why}")]
    Option {
        /// Which option.
        what: &'static str,
        /// Why.
        why: &'static str,
    },
    /// The caller cancelled the run.
    #[error("interrupted")]
    Interrupted,
}

fn disks(spec: &Spec) -> Vec<Disk> {
    spec.requirements.iter().filter_map(|r| r.disk()).collect()
}

/// Most grid points per decade of the design (the tuner doubles them up to three times).
pub const MAX_POINTS_PER_DECADE: usize = 10_000;
/// Most subproblems of one phase of the tuner.
pub const MAX_ITERATIONS: usize = 10_000;

/// Checks every option of the tuner; the error names the first bad one.
pub fn validate(options: &TuneOptions) -> Result<(), TuneError> {
    check(options).map(|_| ())
}

fn check(options: &TuneOptions) -> Result<Objective, TuneError> {
    options.loop_options.check()?;
    for g in [options.target, options.start].iter().flatten() {
        crate::linear::error::check_finite("gains", [g.kp, g.ki, g.kd].iter())?;
    }
    if !(options.max_gain_factor.is_finite() && options.max_gain_factor > 0.0) {
        return Err(TuneError::Option {
            what: "max_gain_factor",
            why: "must be finite and > 0",
        });
    }
    if !(options.effort_tilt.is_finite() && options.effort_tilt > 0.0) {
        return Err(TuneError::Option {
            what: "effort_tilt",
            why: "must be finite and > 0",
        });
    }
    if !(2..=MAX_POINTS_PER_DECADE).contains(&options.points_per_decade) {
        return Err(TuneError::Option {
            what: "points_per_decade",
            why: "must be between 2 and 10000",
        });
    }
    if !(1..=MAX_ITERATIONS).contains(&options.max_iterations) {
        return Err(TuneError::Option {
            what: "max_iterations",
            why: "must be between 1 and 10000",
        });
    }
    let objective = match (options.objective, options.target) {
        (Some(o), _) => o,
        (None, Some(t)) => Objective::Target(t),
        (None, None) if options.pid => Objective::MaxIntegral,
        (None, None) => Objective::MinGain,
    };
    if matches!(objective, Objective::MaxIntegral) && !options.pid {
        return Err(TuneError::Option {
            what: "objective",
            why: "MaxIntegral needs a PID",
        });
    }
    Ok(objective)
}

/// A loop the convex–concave tuner designs for: one whose return ratio is linear in its gains
/// (the pitch PID, the steer loop), with an independent check of the gains it returns.
pub(crate) trait Tunable {
    /// The loop's gains.
    type Gains: Copy;
    /// The independent check of gains.
    type Certificate: Clone;
    /// The design problem on a grid of `points_per_decade`.
    fn design(&self, points_per_decade: usize) -> Result<Design, TuneError>;
    /// The gains of scaled variables.
    fn gains(&self, design: &Design, x: &[f64]) -> Self::Gains;
    /// The independent check of `gains` against `spec`, and whether they meet it.
    fn certify(
        &self,
        gains: &Self::Gains,
        spec: &Spec,
    ) -> Result<(Self::Certificate, bool), LinearError>;
    /// The gains a certificate checked.
    fn certified(certificate: &Self::Certificate) -> Self::Gains;
    /// `x0` if it stabilises the loop, else another stabilising start; `None` if none is found.
    /// The convex–concave steps keep stability only from a stabilising start.
    fn stabilising_start(
        &self,
        design: &Design,
        x0: Vec<f64>,
    ) -> Result<Option<Vec<f64>>, LinearError>;
}

/// How a design ended, for any [`Tunable`] loop.
pub(crate) struct Outcome<C> {
    pub status: TuneStatus,
    pub certificate: Option<C>,
    pub best_fraction: f64,
    pub iterations: usize,
}

impl<C> Outcome<C> {
    fn infeasible() -> Self {
        Self {
            status: TuneStatus::Infeasible,
            certificate: None,
            best_fraction: 0.0,
            iterations: 0,
        }
    }
}

/// The design of `lp` to `spec`: from the start `x0` (of the first design), phase 1 and 2 with
/// the design aiming a little past the spec and a denser grid each time the independent check
/// fails; when phase 1 stalls, the best achievable fraction of the spec.
pub(crate) fn design_run<L: Tunable>(
    lp: &L,
    spec: &Spec,
    goal: &dyn Fn(&Design) -> Goal,
    x0: &dyn Fn(&Design) -> Vec<f64>,
    points_per_decade: usize,
    max_iterations: usize,
    stop: &dyn Fn() -> bool,
) -> Result<Outcome<L::Certificate>, TuneError> {
    let mut design = lp.design(points_per_decade)?;
    let clamped = x0(&design)
        .iter()
        .zip(design.lower.iter().zip(&design.upper))
        .map(|(v, (l, u))| v.clamp(*l, *u))
        .collect();
    let Some(x0) = lp.stabilising_start(&design, clamped)? else {
        return Ok(Outcome::infeasible());
    };
    let mut ppd = points_per_decade;
    let mut start = x0.clone();
    for attempt in 0..4 {
        let aim = spec.scaled(1.0 + 1e-3 * 10f64.powi(attempt));
        let floor = disks(&spec.scaled(level(&design, &start, spec) * (1.0 - 1e-3)));
        match phase1(&design, &start, &disks(&aim), &floor, max_iterations, stop) {
            Phase1::Stalled => break,
            Phase1::Interrupted => return Err(TuneError::Interrupted),
            Phase1::Feasible(x) => {
                let (x, end, iterations) = phase2(
                    &design,
                    &x,
                    &disks(&aim),
                    &goal(&design),
                    max_iterations,
                    stop,
                );
                let (cert, meets) = lp.certify(&lp.gains(&design, &x), spec)?;
                if meets {
                    let status = match end {
                        Phase2End::Converged | Phase2End::SolverFailed(_) => TuneStatus::Solved,
                        Phase2End::IterationLimit => TuneStatus::IterationLimit,
                        Phase2End::Interrupted => return Err(TuneError::Interrupted),
                    };
                    return Ok(Outcome {
                        status,
                        certificate: Some(cert),
                        best_fraction: 1.0,
                        iterations,
                    });
                }
                start = x;
                ppd *= 2;
                design = lp.design(ppd)?;
                if attempt == 3 {
                    return Ok(Outcome {
                        status: TuneStatus::Unverified,
                        certificate: Some(cert),
                        best_fraction: 1.0,
                        iterations,
                    });
                }
            }
        }
    }
    best_achievable(lp, spec, &design, x0, max_iterations, stop)
}

/// The pitch loop with the tuner's options, as a [`Tunable`] loop.
struct PitchDesign<'a> {
    lp: &'a PitchLoop,
    options: &'a TuneOptions,
    /// Kp·tilt ≤ this force bound, from the spec.
    peak_force: Option<f64>,
}

impl Tunable for PitchDesign<'_> {
    type Gains = PidGains;
    type Certificate = Certificate;

    fn design(&self, ppd: usize) -> Result<Design, TuneError> {
        let o = self.options;
        let mut d = Design::new(self.lp, &o.loop_options, o.pid, ppd, o.max_gain_factor).ok_or(
            TuneError::Option {
                what: "model",
                why: "the plant has a pole at its own reference frequency",
            },
        )?;
        if let Some(force) = self.peak_force {
            d.bound_kp(force / o.effort_tilt);
        }
        Ok(d)
    }

    fn gains(&self, design: &Design, x: &[f64]) -> PidGains {
        design.gains(x)
    }

    fn certify(&self, g: &PidGains, spec: &Spec) -> Result<(Certificate, bool), LinearError> {
        let cert = certify(self.lp, g, &self.options.loop_options, spec)?;
        let meets = cert.meets_spec;
        Ok((cert, meets))
    }

    fn certified(c: &Certificate) -> PidGains {
        c.gains
    }

    fn stabilising_start(
        &self,
        design: &Design,
        x0: Vec<f64>,
    ) -> Result<Option<Vec<f64>>, LinearError> {
        stabilising_start(self.lp, design, &self.options.loop_options, x0)
    }
}

/// Tunes the pitch loop `lp` to `spec`.
pub fn tune(lp: &PitchLoop, spec: &Spec, options: &TuneOptions) -> Result<TuneResult, TuneError> {
    tune_with(lp, spec, options, &crate::progress::Silent)
}

/// [`tune`], looking at `progress` for a cancellation before every subproblem.
pub fn tune_with(
    lp: &PitchLoop,
    spec: &Spec,
    options: &TuneOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<TuneResult, TuneError> {
    let stop = || progress.cancelled();
    let objective = check(options)?;
    let outcome = if lp.plant().order() == 0 {
        // The force does not reach Φ: no gains move the loop, no margin can be met.
        Outcome::infeasible()
    } else {
        let pitch = PitchDesign {
            lp,
            options,
            peak_force: spec.peak_force(),
        };
        let x0 = |design: &Design| match options.start.or(options.target) {
            Some(g) => design.scaled(&g),
            // Kp = s_p, Kd = s_d (for the pitch plant 2 M_x g and 2 M_x g/λ: stabilising),
            // Ki = 0, so the start is a PD even when tuning a PID.
            None => {
                let unit = design.gains(&vec![1.0; design.len()]);
                design.scaled(&PidGains { ki: 0.0, ..unit })
            }
        };
        design_run(
            &pitch,
            spec,
            &|d| objective.goal(d),
            &x0,
            options.points_per_decade,
            options.max_iterations,
            &stop,
        )?
    };
    Ok(TuneResult {
        status: outcome.status,
        spec: spec.clone(),
        certificate: outcome.certificate,
        best_fraction: outcome.best_fraction,
        iterations: outcome.iterations,
    })
}

/// Bisection on the fraction t of the spec for the best verified gains.
fn best_achievable<L: Tunable>(
    lp: &L,
    spec: &Spec,
    design: &Design,
    x0: Vec<f64>,
    max_iterations: usize,
    stop: &dyn Fn() -> bool,
) -> Result<Outcome<L::Certificate>, TuneError> {
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut best: Option<L::Certificate> = None;
    let mut x_best = x0;
    for _ in 0..14 {
        let mid = 0.5 * (lo + hi);
        let aim = spec.scaled(mid * (1.0 + 1e-3));
        let floor = disks(&spec.scaled(level(design, &x_best, spec) * (1.0 - 1e-3)));
        let found = match phase1(design, &x_best, &disks(&aim), &floor, max_iterations, stop) {
            Phase1::Feasible(x) => {
                let (cert, meets) = lp.certify(&lp.gains(design, &x), &spec.scaled(mid))?;
                meets.then_some((x, cert))
            }
            Phase1::Stalled => None,
            Phase1::Interrupted => return Err(TuneError::Interrupted),
        };
        match found {
            Some((x, cert)) => {
                lo = mid;
                x_best = x;
                best = Some(cert);
            }
            None => hi = mid,
        }
    }
    // The certificate is always against the spec asked for, so `meets_spec`, the status and
    // every message say the same thing; gains that happen to meet it after all are a solution.
    let (certificate, met) = match best {
        Some(c) => {
            let (cert, meets) = lp.certify(&L::certified(&c), spec)?;
            (Some(cert), meets)
        }
        None => (None, false),
    };
    Ok(Outcome {
        status: if met {
            TuneStatus::Solved
        } else {
            TuneStatus::Infeasible
        },
        certificate,
        best_fraction: if met { 1.0 } else { lo },
        iterations: 0,
    })
}

/// The largest t ∈ [0, 1] for which x keeps L out of the disks of `spec.scaled(t)` on the
/// design grid (bisection; the disks grow with t).
fn level(design: &Design, x: &[f64], spec: &Spec) -> f64 {
    let meets = |t: f64| design.violation(x, &disks(&spec.scaled(t))) <= 0.0;
    if meets(1.0) {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if meets(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Disk margin α of a stable loop on a coarse grid, `None` if unstable (eigenvalues, or the
/// delay beyond the delay margin). Cheap enough to scan gains with.
fn coarse_alpha(
    lp: &PitchLoop,
    g: &PidGains,
    opts: &LoopOptions,
) -> Result<Option<f64>, LinearError> {
    let closed = lp.closed_loop(g, opts)?;
    if !closed.stable {
        return Ok(None);
    }
    let scales = crate::linear::report::loop_scales(lp, g, opts, &closed)?;
    let mut grid = GridOptions::around(&scales);
    grid.points_per_decade = 20;
    grid.refine_floor = 0.1;
    let l0 = |w: f64| lp.loop_delay_free(g, opts.lag, w);
    let m = loop_margins(&l0, opts.delay, true, &grid);
    Ok(m.stable.then_some(m.disk.alpha))
}

/// The start if it stabilises the loop, else the PD gains (Ki = 0) of a 12 × 12 log scan over
/// [0.03, 30] times the gain scales with the largest disk margin; `None` if none stabilises.
/// The convex–concave steps keep stability only from a stabilising start.
fn stabilising_start(
    lp: &PitchLoop,
    design: &Design,
    opts: &LoopOptions,
    x0: Vec<f64>,
) -> Result<Option<Vec<f64>>, LinearError> {
    if coarse_alpha(lp, &design.gains(&x0), opts)?.is_some() {
        return Ok(Some(x0));
    }
    let unit = design.gains(&vec![1.0; design.len()]);
    let mut best: Option<(f64, Vec<f64>)> = None;
    for i in 0..12 {
        for j in 0..12 {
            let f = |k: i32| 0.03 * 1000f64.powf(f64::from(k) / 11.0);
            let g = PidGains {
                kp: unit.kp * f(i),
                ki: 0.0,
                kd: unit.kd * f(j),
            };
            let x = design.scaled(&g);
            let inside = x.iter().zip(&design.upper).all(|(v, u)| v <= u);
            if !inside {
                continue;
            }
            if let Some(alpha) = coarse_alpha(lp, &g, opts)? {
                if !best.as_ref().is_some_and(|b| alpha <= b.0) {
                    best = Some((alpha, x));
                }
            }
        }
    }
    Ok(best.map(|b| b.1))
}
