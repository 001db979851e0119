//! Pitch-loop gains fitted to a margin specification with Clarabel, with the independent
//! certificate and a tilt recovery on the nonlinear model: `twv tune`.

use serde::{Deserialize, Serialize};
use twv_model::Model;

use super::linear::pitch_loop;
use super::simulate::{simulate, Recovery, SimSettings};
use crate::control::{ControllerSettings, RunSettings};
use crate::error::Result;
use crate::linear::{linearize, OperatingPoint, PidGains};
use crate::model::{dispatch, ModelTask, ResolvedModel};
use crate::progress::Progress;
use crate::tune::{tune_with, Spec, TuneOptions, TuneResult, TuneStatus};

/// What to tune. Defaults: `dpm>=45`, a PD with the smallest gains that meet it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TuneSettings {
    /// The specification.
    pub spec: Spec,
    /// The tuner's options (PD or PID, objective, target, lag and delay, …).
    pub options: TuneOptions,
    /// Check the certificate's gains on the nonlinear model after a tilt of this size [rad]
    /// (also the tilt of a `force<=` bound). Default 0.1.
    pub tilt: f64,
}

impl Default for TuneSettings {
    fn default() -> Self {
        Self {
            spec: "dpm>=45".parse().expect("a valid default spec"),
            options: TuneOptions::default(),
            tilt: 0.1,
        }
    }
}

/// The certificate's gains on the nonlinear model after a tilt (the same code as
/// `twv disturb`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TiltCheck {
    /// The tilt [rad].
    pub tilt: f64,
    /// Whether Φ recovered (see [`Recovery`]).
    pub recovery: Recovery,
    /// 2 % settling time [s].
    pub settling_time: Option<f64>,
    /// Overshoot as a fraction of the tilt.
    pub overshoot: Option<f64>,
    /// Peak |F| [N].
    pub peak_force: f64,
    /// Φ at the end [rad].
    pub final_phi: f64,
}

/// How the tuning ended, all things considered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TuneVerdict {
    /// Gains found that meet every requirement: the margins (independent check), the effort
    /// bound if any, and a recovery from the tilt on the nonlinear model.
    Met,
    /// Gains meet the linear margins but the nonlinear check fails (no recovery, or a peak
    /// force above the `force<=` bound).
    NonlinearCheckFailed,
    /// No gains meeting the margins were found (the method is local: not a proof that none
    /// exist); the certificate is that of the best gains found.
    Infeasible,
    /// The tuner stopped otherwise (gains that never passed the independent check).
    NotVerified,
}

/// The tuner's answer with the model it was computed for.
#[derive(Debug, Clone, Serialize)]
pub struct TuneReport {
    /// Model name.
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// The verdict: every message and the exit code follow it.
    pub verdict: TuneVerdict,
    /// The tuner's result and certificate.
    pub result: TuneResult,
    /// The nonlinear check of the certificate's gains.
    pub tilt_check: Option<TiltCheck>,
}

fn verdict(result: &TuneResult, tilt: Option<&TiltCheck>, spec: &Spec) -> TuneVerdict {
    match result.status {
        TuneStatus::Infeasible => TuneVerdict::Infeasible,
        TuneStatus::Unverified => TuneVerdict::NotVerified,
        _ if !result.met() => TuneVerdict::NotVerified,
        _ => match tilt {
            Some(t)
                if t.recovery == Recovery::Recovered
                    && spec.peak_force().is_none_or(|f| t.peak_force <= f) =>
            {
                TuneVerdict::Met
            }
            _ => TuneVerdict::NonlinearCheckFailed,
        },
    }
}

/// The tilt recovery with `gains` on the nonlinear model.
pub fn tilt_check(model: &ResolvedModel, gains: &PidGains, tilt: f64) -> Result<TiltCheck> {
    let out = simulate(
        model,
        &SimSettings {
            title: format!("certificate: tilt of {tilt} rad"),
            scenario: "forward tilt".into(),
            controller: ControllerSettings::pid(*gains),
            run: RunSettings::default(),
            x0: None,
            phi0: tilt,
            ..SimSettings::default()
        },
        &crate::progress::Silent,
    )?;
    let m = &out.metrics;
    Ok(TiltCheck {
        tilt,
        recovery: out.recovery,
        settling_time: m.phi.settling_time,
        overshoot: m.phi.overshoot,
        peak_force: m.peak_force,
        final_phi: m.final_phi,
    })
}

struct Fit<'a>(&'a TuneSettings, &'a dyn Progress);

impl ModelTask for Fit<'_> {
    type Output = TuneResult;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<TuneResult> {
        let lin = linearize(model, &OperatingPoint::Upright, &[0.0; NU])?;
        let lp = pitch_loop(&lin, &model.info(), resolved)?;
        let options = TuneOptions {
            effort_tilt: self.0.tilt,
            ..self.0.options
        };
        Ok(tune_with(&lp, &self.0.spec, &options, self.1)?)
    }
}

/// Tunes the pitch loop of `model` and checks the gains on the nonlinear model.
pub fn tune_model(model: &ResolvedModel, settings: &TuneSettings) -> Result<TuneReport> {
    tune_model_with(model, settings, &crate::progress::Silent)
}

/// [`tune_model`], stopping at the next subproblem when `progress` says it is cancelled.
pub fn tune_model_with(
    model: &ResolvedModel,
    settings: &TuneSettings,
    progress: &dyn Progress,
) -> Result<TuneReport> {
    if !(settings.tilt.is_finite() && settings.tilt > 0.0) {
        return Err(crate::error::Error::input(
            "tilt",
            format!("{} must be a finite angle > 0 rad", settings.tilt),
        ));
    }
    let result = dispatch(model, Fit(settings, progress))?;
    let tilt = match &result.certificate {
        Some(c) if c.analysis.closed_loop.stable => {
            Some(tilt_check(model, &c.gains, settings.tilt)?)
        }
        _ => None,
    };
    Ok(TuneReport {
        model: model.name().to_string(),
        params: model.params_origin.clone(),
        verdict: verdict(&result, tilt.as_ref(), &settings.spec),
        result,
        tilt_check: tilt,
    })
}

impl TuneReport {
    /// A readable summary of the result, its certificate and the verdict.
    pub fn summary(&self) -> String {
        let res = &self.result;
        let mut s = format!(
            "tune {} ({}) to {}: {}\n",
            self.model,
            self.params,
            res.spec,
            match self.verdict {
                TuneVerdict::Met if res.status == TuneStatus::IterationLimit => format!(
                    "margins met, but the objective had not converged when the tuner stopped \
                     at its limit of {} subproblems: these are the last gains that met the \
                     specification, not an optimum (an objective without a bound, such as \
                     max-proportional without a force<= requirement, grows the gains until the \
                     limit)",
                    res.iterations
                ),
                TuneVerdict::Met => format!(
                    "met ({:?} after {} subproblems)",
                    res.status, res.iterations
                ),
                TuneVerdict::NonlinearCheckFailed =>
                    "margins met, but the nonlinear check FAILED".to_string(),
                TuneVerdict::Infeasible => format!(
                    "INFEASIBLE: the best gains found reach {:.1} % of the specification (the \
                     method is local: no gains found, not a proof that none exist)",
                    100.0 * res.best_fraction
                ),
                TuneVerdict::NotVerified => format!("NOT verified ({:?})", res.status),
            }
        );
        if let Some(c) = &res.certificate {
            let g = &c.gains;
            let m = &c.analysis.margins;
            s += &format!(
                "  gains Kp = {:.4}, Ki = {:.4}, Kd = {:.4}{}\n",
                g.kp,
                g.ki,
                g.kd,
                if self.verdict == TuneVerdict::Infeasible {
                    " (best found)"
                } else {
                    ""
                }
            );
            if c.analysis.closed_loop.stable {
                s += &format!(
                    "  certificate (independent check): closed loop stable, disk phase margin {:.2}°, disk gain margin [{:.4}, {}], peak |S| {:.3}: spec {}\n",
                    m.disk.phase_deg,
                    m.disk.gain_low,
                    if m.disk.gain_high.is_finite() { format!("{:.4}", m.disk.gain_high) } else { "unbounded".into() },
                    m.peak_sensitivity,
                    if c.meets_spec { "met" } else { "NOT met" }
                );
            } else {
                s += "  certificate (independent check): closed loop UNSTABLE: spec NOT met\n";
            }
        }
        if let Some(t) = &self.tilt_check {
            s += &format!(
                "  nonlinear check: after a {} rad forward tilt Φ {} (2 % settling {}, peak force {:.1} N{})\n",
                t.tilt,
                match t.recovery {
                    Recovery::Recovered => "recovers",
                    Recovery::NotSettled => "does NOT settle",
                    Recovery::Fell => "FALLS",
                },
                t.settling_time.map_or("—".into(), |v| format!("{v:.3} s")),
                t.peak_force,
                match res.spec.peak_force() {
                    Some(f) if t.peak_force > f => format!(" > the bound {f} N"),
                    Some(f) => format!(" ≤ the bound {f} N"),
                    None => String::new(),
                }
            );
        }
        s
    }
}
