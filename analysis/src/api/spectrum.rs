//! The Lyapunov spectrum of a model, open loop or under the PID controller: `twv lyap`.

use std::time::Instant;

use serde::{Deserialize, Serialize};
use twv_model::{Model, ModelInfo};

use super::steady::steady_state;
use crate::control::steer::{FilteredSteer, SteerLaw, SteerSettings};
use crate::control::{ControllerSettings, PidLoop, Plant};
use crate::error::{Error, Result};
use crate::integrate::{ClosedLoop, OpenLoop, VectorField};
use crate::lyapunov::{lyapunov_spectrum_observed, LyapunovResult, LyapunovSettings};
use crate::model::{
    dispatch, dispatch_control, dispatch_steer_filtered, dispatch_steered, input_vector,
    state_vector, ControlTask, ModelTask, ResolvedModel,
};
use crate::output::Files;
use crate::plot::{Curve, Figure, LineChart};
use crate::progress::Progress;

/// What to compute. Defaults: the study's preset from rest... (`x0` must be given), u = 0,
/// open loop, the full spectrum.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpectrumSettings {
    /// Initial model state, in the model's state order (controller states start at 0); empty
    /// with `speed`.
    pub x0: Vec<f64>,
    /// Start from the model's steady motion at this speed [m/s] instead of `x0` (models whose
    /// IR describes straight running: the bicycle).
    pub speed: Option<f64>,
    /// Steer the model by this steer-torque law (a model with a steer input: the bicycle);
    /// the spectrum is the steered bicycle's. `None`: not steered.
    pub steer: Option<SteerSettings>,
    /// Constant input of an open-loop run; `None`: zeros.
    pub u: Option<Vec<f64>>,
    /// Closed loop under this controller; `None`: open loop.
    pub controller: Option<ControllerSettings>,
    /// The Benettin–QR settings.
    pub lyapunov: LyapunovSettings,
    /// Number of exponents (1 to the state dimension); `None`: the full spectrum.
    pub exponents: Option<usize>,
    /// Repeat the computation this many times and report the wall time per run (benchmarks).
    pub repeat: Option<usize>,
}

/// A spectrum with the run that produced it.
#[derive(Debug, Clone, Serialize)]
pub struct SpectrumResult {
    /// Model name (with "(closed loop)" for a controlled run).
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// Initial state (model states, then controller states).
    pub x0: Vec<f64>,
    /// Constant input (open loop).
    pub u: Vec<f64>,
    /// The settings used.
    pub settings: LyapunovSettings,
    /// The controller of a closed-loop spectrum.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerSettings>,
    /// The steady motion's speed the run started from [m/s], and the steer law of a steered
    /// spectrum.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steer: Option<SteerSettings>,
    /// The spectrum and its diagnostics.
    #[serde(flatten)]
    pub result: LyapunovResult,
    /// States no other state's rate depends on (from the structure of ∂f/∂x): each gives an
    /// exact zero exponent (drift and symmetry directions such as position and heading).
    pub drift_states: Vec<String>,
    /// Wall time per run when `repeat` was asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
}

/// Wall time of repeated runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// Runs timed.
    pub runs: usize,
    /// Seconds per run.
    pub seconds_per_run: f64,
}

impl SpectrumSettings {
    /// Checks the settings that do not depend on the model.
    pub fn validate(&self) -> Result<()> {
        self.lyapunov.validate()?;
        if let Some(c) = &self.controller {
            c.validate()?;
        }
        if self.repeat == Some(0) {
            return Err(Error::input("repeat", "needs at least one run"));
        }
        if self.exponents == Some(0) {
            return Err(Error::input("exponents", "need at least one exponent"));
        }
        if let Some(v) = self.speed {
            super::check_speed(v)?;
            if !self.x0.is_empty() {
                return Err(Error::input(
                    "speed",
                    "give either an initial state (x0) or a speed, not both",
                ));
            }
        }
        if let Some(law) = &self.steer {
            law.validate()?;
            if self.controller.is_some() {
                return Err(Error::input(
                    "steer_gains",
                    "the steer law and the pitch controller are two different loops: give one",
                ));
            }
        }
        if self.controller.is_some() && self.u.is_some() {
            return Err(Error::input(
                "u",
                "a closed loop computes its inputs: drop the constant input",
            ));
        }
        Ok(())
    }
}

/// The spectrum with `k` exponents: one tangent vector for k = 1 (the cheap largest exponent),
/// otherwise the full spectrum, cut to the `k` largest (the same values: the first k columns of
/// a QR do not depend on the others), so each model needs only two instantiations.
fn exponents_of<F: VectorField<N>, const N: usize>(
    field: &F,
    x0: &[f64; N],
    k: usize,
    settings: &LyapunovSettings,
    progress: &dyn Progress,
) -> Result<LyapunovResult> {
    Ok(match k {
        1 => lyapunov_spectrum_observed::<_, N, 1>(field, x0, settings, progress)?,
        k if (2..=N).contains(&k) => {
            lyapunov_spectrum_observed::<_, N, N>(field, x0, settings, progress)?.largest(k)
        }
        k => {
            return Err(Error::input(
                "exponents",
                format!("{k}: choose 1 to {N} (the full spectrum)"),
            ))
        }
    })
}

/// The spectrum, repeated for the wall time per run when asked.
fn timed<F: VectorField<N>, const N: usize>(
    s: &SpectrumSettings,
    field: &F,
    x0: &[f64; N],
    progress: &dyn Progress,
) -> Result<(LyapunovResult, Option<Timing>)> {
    let k = s.exponents.unwrap_or(N);
    let mut result = exponents_of(field, x0, k, &s.lyapunov, progress)?;
    let timing = match s.repeat {
        Some(runs) => {
            let start = Instant::now();
            for _ in 0..runs {
                result = exponents_of(field, x0, k, &s.lyapunov, progress)?;
            }
            Some(Timing {
                runs,
                seconds_per_run: start.elapsed().as_secs_f64() / runs as f64,
            })
        }
        None => None,
    };
    Ok((result, timing))
}

/// States whose columns of ∂f/∂x have structural entries only in the rows of states found
/// before them: no other state's rate depends on them, and ∂f/∂x is nilpotent on them, so each
/// contributes an exact zero exponent (x, y, then θ for a vehicle).
pub fn drift_states(model: &ResolvedModel) -> Vec<String> {
    let Some(jac) = model.ir.jac_x_sparsity() else {
        return Vec::new();
    };
    let nx = model.ir.nx();
    let rows_of = |j: usize| &jac.row[jac.colind[j]..jac.colind[j + 1]];
    let mut drift = vec![false; nx];
    loop {
        let next = (0..nx).find(|&j| !drift[j] && rows_of(j).iter().all(|&r| drift[r] && r != j));
        match next {
            Some(j) => drift[j] = true,
            None => break,
        }
    }
    let states = model.states();
    (0..nx)
        .filter(|&j| drift[j])
        .map(|j| states[j].to_string())
        .collect()
}

/// What each task returns: the start (x0, and u when open), the result and its timing.
type Run = (Vec<f64>, Vec<f64>, LyapunovResult, Option<Timing>);

struct Open<'a>(&'a SpectrumSettings, &'a dyn Progress);

/// x0 and the constant inputs (0 unless given) of `s` on a model.
fn start<const NX: usize, const NU: usize>(
    s: &SpectrumSettings,
    info: &ModelInfo,
) -> Result<([f64; NX], [f64; NU])> {
    let x0 = state_vector("x0", &s.x0, info.states)?;
    let u = match &s.u {
        Some(u) => input_vector("u", u, info.inputs)?,
        None => [0.0; NU],
    };
    Ok((x0, u))
}

impl ModelTask for Open<'_> {
    type Output = Run;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        _: &ResolvedModel,
    ) -> Result<Self::Output> {
        let info = model.info();
        let (x0, u) = start::<NX, NU>(self.0, &info)?;
        let (result, timing) = timed(self.0, &OpenLoop::new(model, u), &x0, self.1)?;
        Ok((x0.to_vec(), u[..info.inputs.len()].to_vec(), result, timing))
    }
}

/// The spectrum of the model steered by a law without a rate filter.
struct Steered<'a>(&'a SpectrumSettings, SteerSettings, &'a dyn Progress);

impl ModelTask for Steered<'_> {
    type Output = Run;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output> {
        let info = model.info();
        let (x0, u) = start::<NX, NU>(self.0, &info)?;
        let law = SteerLaw::<NX, NU>::for_model(resolved, info.states, info.inputs, &self.1, u)?;
        let (result, timing) = timed(self.0, &ClosedLoop::new(model, law), &x0, self.2)?;
        Ok((x0.to_vec(), u[..info.inputs.len()].to_vec(), result, timing))
    }
}

struct Closed<'a>(
    &'a SpectrumSettings,
    &'a ControllerSettings,
    &'a dyn Progress,
);

impl ControlTask for Closed<'_> {
    type Output = Run;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output> {
        let x0: [f64; NX] = state_vector("x0", &self.0.x0, model.info().states)?;
        let plant = Plant::from_info(&model.info(), &|n| resolved.param(n))?;
        let field = PidLoop::<_, NX, NU, NA>::new(model, self.1, plant)?;
        let xa = field.initial_state(&x0);
        let (result, timing) = timed(self.0, &field, &xa, self.2)?;
        Ok((xa.to_vec(), Vec::new(), result, timing))
    }
}

/// The spectrum of the model steered by a law with a rate filter: on NA = NX + 2 states, from
/// x0 and the filter at its rates.
struct FilteredSteered<'a>(&'a SpectrumSettings, SteerSettings, &'a dyn Progress);

impl ControlTask for FilteredSteered<'_> {
    type Output = Run;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output> {
        let info = model.info();
        let (x0, u) = start::<NX, NU>(self.0, &info)?;
        let law = SteerLaw::<NX, NU>::for_model(resolved, info.states, info.inputs, &self.1, u)?;
        let field = FilteredSteer::<_, NX, NU, NA>::new(model, law)?;
        let xa = field.initial_state(&x0);
        let (result, timing) = timed(self.0, &field, &xa, self.2)?;
        Ok((xa.to_vec(), u[..info.inputs.len()].to_vec(), result, timing))
    }
}

/// The Lyapunov spectrum of `model` with `settings`.
pub fn spectrum(
    model: &ResolvedModel,
    settings: &SpectrumSettings,
    progress: &dyn Progress,
) -> Result<SpectrumResult> {
    settings.validate()?;
    // From the steady motion at a speed: its state is the initial state.
    let at_speed;
    let settings = match settings.speed {
        Some(v) => {
            at_speed = SpectrumSettings {
                x0: steady_state(model, v)?,
                ..settings.clone()
            };
            &at_speed
        }
        None => settings,
    };
    if settings.x0.is_empty() {
        return Err(Error::input(
            "x0",
            "the spectrum needs an initial state (x0) or a speed",
        ));
    }
    let ((x0, u, result, timing), name) = match (&settings.controller, settings.steer) {
        (Some(c), _) => (
            dispatch_control(model, c.n_states(), Closed(settings, c, progress))?,
            format!("{} (closed loop)", model.name()),
        ),
        (None, Some(law)) if law.rate_filter.is_some() => (
            dispatch_steer_filtered(model, FilteredSteered(settings, law, progress))?,
            format!("{} (steered, rate filter)", model.name()),
        ),
        (None, Some(law)) => (
            dispatch_steered(model, Steered(settings, law, progress))?,
            format!("{} (steered)", model.name()),
        ),
        (None, None) => (
            dispatch(model, Open(settings, progress))?,
            model.name().to_string(),
        ),
    };
    Ok(SpectrumResult {
        model: name,
        params: model.params_origin.clone(),
        x0,
        u,
        settings: settings.lyapunov.clone(),
        controller: settings.controller.clone(),
        speed: settings.speed,
        steer: settings.steer,
        result,
        drift_states: drift_states(model),
        timing,
    })
}

impl SpectrumResult {
    /// Why zero exponents are expected, from the model's structure (empty without drift
    /// states).
    pub fn drift_note(&self) -> String {
        if self.drift_states.is_empty() {
            return String::new();
        }
        format!(
            "exact zero exponents are expected from {}: no other state's rate depends on them \
             (structure of ∂f/∂x)",
            self.drift_states.join(", ")
        )
    }

    /// The running-estimates figure (the study's Fig. 3), on a logarithmic time axis so the
    /// early transient and the long-time values are both visible.
    pub fn running_figure(&self) -> Figure {
        let running = &self.result.running;
        let curves = (0..running.k)
            .map(|j| Curve {
                name: format!("λ{}", j + 1),
                points: (0..running.len())
                    .map(|i| (running.t[i], running.row(i)[j]))
                    .collect(),
            })
            .collect();
        let title = format!("Lyapunov exponents of {}: running estimates", self.model);
        Figure::Line(LineChart {
            log_x: true,
            ..LineChart::new(&title, "t [s] (log scale)", "λ [1/s]", (900, 520), curves)
        })
    }

    /// lyapunov.json, running.csv and the running-estimates figure (SVG and PNG).
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.json("lyapunov.json", self);
        f.text("running.csv", self.running_csv());
        f.figure("running.svg", &self.running_figure())?;
        Ok(f)
    }

    /// The running estimates as CSV.
    pub fn running_csv(&self) -> String {
        let mut csv = Vec::new();
        // Writing into a Vec cannot fail.
        let _ = self.result.running.write_csv(&mut csv);
        String::from_utf8(csv).unwrap_or_default()
    }

    /// A few readable lines; ± is one standard error (batch means), the sign tests use z of
    /// them.
    pub fn summary(&self) -> String {
        let r = &self.result;
        let mut s = format!(
            "Lyapunov spectrum of {} over {:.3} s ({})\n",
            self.model, r.t_total, self.params
        );
        for (i, ((l, e), d)) in r.exponents.iter().zip(&r.stderr).zip(&r.signs).enumerate() {
            // Fewer than two batches have no spread: the error is unknown, not a number.
            let error = if e.is_nan() {
                "(no error: fewer than two batches)".to_string()
            } else {
                format!("± {e:.6} 1/s (1σ)")
            };
            s += &format!(
                "  λ{:<2} = {:+.6} {error}  {:?}: {}\n",
                i + 1,
                l,
                d.sign,
                d.test
            );
        }
        s += &format!(
            "  sign tests: z = {} (significant beyond {}σ), floor {:.3e} 1/s\n",
            r.significance, r.significance, r.zero_floor
        );
        s += &format!("  Σλ      = {:+.10e}\n", r.sum);
        if let Some(tr) = r.mean_trace {
            s += &format!(
                "  ⟨tr J⟩  = {tr:+.10e}   (relative difference {:.2e})\n",
                r.trace_residual().unwrap_or(f64::NAN)
            );
        }
        if let Some(ky) = r.kaplan_yorke {
            s += &format!("  Kaplan–Yorke dimension {ky:.4}\n");
        }
        s += &format!("  {}\n", r.classification);
        let note = self.drift_note();
        if !note.is_empty() {
            s += &format!("  ({note})\n");
        }
        if let Some(t) = &self.timing {
            s += &format!(
                "  {:.4} ms per run ({} runs)\n",
                1e3 * t.seconds_per_run,
                t.runs
            );
        }
        s
    }
}
