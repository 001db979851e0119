//! `lyapunov`: the Lyapunov spectrum (Benettin–QR) of a model, open loop or under the pitch
//! controller, with running estimates, error bars and Σλ = ⟨tr J⟩.

use serde_json::{json, Value};

use super::groups::{controller, integrator, optional, steer};
use super::options::{
    as_choice, as_integer, field, flag, integer, is_none, number, optional_number, optional_vector,
    sub, vector, Kind, Opt,
};
use super::{steps, Budget, Job, JobOutput};
use crate::api::{spectrum, SpectrumResult, SpectrumSettings};
use crate::error::{Error, Result};
use crate::lyapunov::{InitialBasis, LyapunovSettings};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The Lyapunov spectrum.
pub struct Lyapunov;

fn optional_count(name: &str, v: &Value) -> Result<Option<usize>> {
    if is_none(v) {
        return Ok(None);
    }
    let n = as_integer(name, v)?;
    usize::try_from(n)
        .map(Some)
        .map_err(|_| Error::input(name, format!("{n} is too large")))
}

impl Job for Lyapunov {
    const NAME: &'static str = "lyapunov";
    const ALIASES: &'static [&'static str] = &["lyap", "spectrum", "lyapunov_spectrum"];
    const FILES: &'static str =
        "lyapunov.json, running.csv and running.svg/.png (the running estimates)";
    const SUMMARY: &'static str =
        "Lyapunov spectrum (Benettin–QR) with running estimates, errors and Σλ = ⟨tr J⟩";
    type Settings = SpectrumSettings;
    type Output = SpectrumResult;

    fn options() -> Vec<Opt<SpectrumSettings>> {
        let mut opts = vec![
            vector(
                "x0",
                "SI, rad",
                "Initial state, in the model's state order (or --speed)",
                field(|s: &mut SpectrumSettings| &mut s.x0),
            )
            .positional(),
            optional_number(
                "speed",
                "m/s",
                "Start from the model's steady motion at this speed instead of x0 (models whose \
                 IR describes one, e.g. whipple)",
                field(|s: &mut SpectrumSettings| &mut s.speed),
            )
            .conflicts(&["x0"]),
            optional_vector(
                "u",
                "N, N m",
                "Constant input of an open-loop run (none: zeros)",
                field(|s: &mut SpectrumSettings| &mut s.u),
            ),
        ];
        // The steered bicycle: a steer-torque law closes its steer loop.
        opts.extend(steer(|s: &mut SpectrumSettings| &mut s.steer));
        // The closed loop: the spectrum is that of model and controller states together.
        opts.extend(controller(
            optional(|s: &mut SpectrumSettings| &mut s.controller),
            true,
        ));
        opts.push(
            Opt::new(
                "preset",
                Kind::Choice,
                "",
                "Start from a preset (paper: the study's T = 0.1 s, K = 100, RK4 with h = 1 ms); \
                 the options below override it",
                |s: &mut SpectrumSettings, v| {
                    as_choice("preset", v, &["paper"])?;
                    let running = s.lyapunov.record_running;
                    s.lyapunov = LyapunovSettings {
                        record_running: running,
                        ..LyapunovSettings::preset_paper()
                    };
                    Ok(())
                },
                |_| Value::Null,
            )
            .choices(&["paper"]),
        );
        let lyap = field(|s: &mut SpectrumSettings| &mut s.lyapunov);
        opts.push(
            number(
                "qr_interval",
                "s",
                "Re-orthonormalisation interval T",
                sub(lyap.clone(), |l| &mut l.t_sample),
            )
            .aliases(&["t_sample"]),
        );
        opts.push(integer(
            "iterations",
            "",
            "Number of intervals K averaged over",
            sub(lyap.clone(), |l| &mut l.iterations),
        ));
        opts.push(number(
            "transient",
            "s",
            "Time discarded before averaging",
            sub(lyap.clone(), |l| &mut l.transient),
        ));
        opts.extend(integrator(sub(lyap.clone(), |l| &mut l.integrator), true));
        opts.push(
            Opt::new(
                "k",
                Kind::Integer,
                "",
                "Number of exponents, 1 to the state dimension (none: all)",
                |s: &mut SpectrumSettings, v| {
                    s.exponents = optional_count("k", v)?;
                    Ok(())
                },
                |s| json!(s.exponents),
            )
            .aliases(&["exponents"]),
        );
        opts.push(Opt::new(
            "seed",
            Kind::Integer,
            "",
            "Random orthonormal initial tangent basis from this seed (none: the identity basis)",
            |s: &mut SpectrumSettings, v| {
                s.lyapunov.basis = if is_none(v) {
                    InitialBasis::Identity
                } else {
                    InitialBasis::Random {
                        seed: as_integer("seed", v)?,
                    }
                };
                Ok(())
            },
            |s| match s.lyapunov.basis {
                InitialBasis::Identity => Value::Null,
                InitialBasis::Random { seed } => json!(seed),
            },
        ));
        opts.push(optional_number(
            "zero_floor",
            "1/s",
            "Absolute floor of the sign tests (none: ln(K²)/T over the horizon T)",
            sub(lyap.clone(), |l| &mut l.zero_floor),
        ));
        opts.push(
            flag(
                "running",
                "Record the running estimates (running.csv and its figure)",
                sub(lyap, |l| &mut l.record_running),
            )
            .aliases(&["record_running"]),
        );
        opts.push(
            Opt::new(
                "timing",
                Kind::Integer,
                "",
                "Repeat the computation N times and report the wall time per run (benchmarks)",
                |s: &mut SpectrumSettings, v| {
                    s.repeat = optional_count("timing", v)?;
                    Ok(())
                },
                |s| json!(s.repeat),
            )
            .aliases(&["repeat"]),
        );
        opts
    }

    fn validate(s: &SpectrumSettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &SpectrumSettings) -> Result<Budget> {
        let l = &s.lyapunov;
        let horizon = l.transient + l.horizon();
        let runs = s.repeat.unwrap_or(1) as f64;
        Ok(Budget {
            horizon,
            steps: runs * steps(horizon, &l.integrator),
            samples: if l.record_running {
                l.iterations as f64
            } else {
                0.0
            },
            points: runs,
            ..Budget::default()
        })
    }

    fn run(
        model: &ResolvedModel,
        s: &SpectrumSettings,
        progress: &dyn Progress,
    ) -> Result<SpectrumResult> {
        spectrum(model, s, progress)
    }
}

impl JobOutput for SpectrumResult {
    fn summary(&self) -> String {
        SpectrumResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        SpectrumResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(self.running_csv())
    }
}
