//! `sweep`: a stability map over (Kp, Kd[, Ki]) and model parameters, in memory (the command
//! line's `twv sweep` writes it as resumable shards instead).

use serde::Serialize;
use serde_json::{json, Value};

use super::groups::{controller, one};
use super::options::{
    as_choice, as_vector, field, integer, is_none, number, optional_vector, sub, Kind, Opt,
};
use super::{Budget, Job, JobOutput};
use crate::api::{status_counts, sweep, SweepSettings};
use crate::control::STUDY_PD;
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::progress::Progress;
use crate::sweep::{Axis, Metric, ParamAxis, PointResult};

/// The stability map.
pub struct Sweep;

/// The map's points, in index order (Kp fastest, then Kd, Ki and the parameter axes).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(transparent)]
pub struct SweepPoints(pub Vec<PointResult>);

const METRICS: &[&str] = &["max-lyapunov", "spectral-abscissa", "settling-time"];

/// An axis from `A:B:N` or `[lo, hi, n]`.
pub(super) fn axis(name: &'static str, v: &Value) -> Result<Axis> {
    match v {
        Value::String(text) => Ok(Axis::parse(name, text)?),
        Value::Array(_) => {
            let x = as_vector(name, v)?;
            let [lo, hi, n] = x[..] else {
                return Err(Error::input(name, "wants three numbers [lo, hi, n]"));
            };
            if !(n >= 1.0 && n.fract() == 0.0) {
                return Err(Error::input(
                    name,
                    format!("n = {n} must be a whole number ≥ 1"),
                ));
            }
            Ok(Axis {
                lo,
                hi,
                n: n as usize,
            })
        }
        Value::Object(_) => {
            serde_json::from_value(v.clone()).map_err(|e| Error::input(name, e.to_string()))
        }
        _ => Err(Error::input(name, "wants an axis A:B:N (or [lo, hi, n])")),
    }
}

pub(super) fn axis_text(a: &Axis) -> Value {
    json!(format!("{}:{}:{}", a.lo, a.hi, a.n))
}

/// Parameter axes from `NAME=A:B:N` texts (a list, or one separated by `;`), or an object
/// `{name: [lo, hi, n]}`.
fn param_axes(v: &Value) -> Result<Vec<ParamAxis>> {
    let texts: Vec<Value> = match v {
        Value::String(t) => t
            .split(';')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(|p| Value::String(p.to_string()))
            .collect(),
        Value::Array(items) => items.clone(),
        Value::Object(map) => {
            return map
                .iter()
                .map(|(name, x)| {
                    let a = axis("param", x)?;
                    Ok(ParamAxis {
                        name: name.clone(),
                        lo: a.lo,
                        hi: a.hi,
                        n: a.n,
                    })
                })
                .collect()
        }
        _ => return Err(Error::input("param", "wants NAME=A:B:N axes")),
    };
    texts
        .iter()
        .map(|t| match t {
            Value::String(s) => Ok(ParamAxis::parse(s)?),
            other => Ok(serde_json::from_value(other.clone())
                .map_err(|e| Error::input("param", e.to_string()))?),
        })
        .collect()
}

fn gain_axis(
    name: &'static str,
    help: &'static str,
    unit: &'static str,
    f: fn(&mut crate::sweep::Grid) -> &mut Axis,
) -> Opt<SweepSettings> {
    Opt::new(
        name,
        Kind::Text,
        unit,
        help,
        move |s: &mut SweepSettings, v| {
            *f(&mut s.grid) = axis(name, v)?;
            Ok(())
        },
        move |s| axis_text(f(&mut s.grid.clone())),
    )
}

impl Job for Sweep {
    const NAME: &'static str = "sweep";
    const ALIASES: &'static [&'static str] = &["map"];
    const SUMMARY: &'static str =
        "Stability map over PID gains and model parameters (in memory; the CLI writes resumable \
         shards for Slurm/Kubernetes arrays)";
    type Settings = SweepSettings;
    type Output = SweepPoints;

    fn options() -> Vec<Opt<SweepSettings>> {
        let mut opts =
            vec![
            Opt::new(
                "param",
                Kind::Text,
                "",
                "Model parameter axes NAME=A:B:N (the IR's parameter names: m2, b, I2_xx, …; \
                 several separated by `;`), each varying slower than the gains and than the \
                 axes before it; with them the gains stay at the study's PD unless kp and kd \
                 are given",
                |s: &mut SweepSettings, v| {
                    s.grid.params = param_axes(v)?;
                    if !s.grid.params.is_empty() {
                        s.grid.kp = Axis::point(STUDY_PD.kp);
                        s.grid.kd = Axis::point(STUDY_PD.kd);
                    }
                    Ok(())
                },
                |s| {
                    json!(s
                        .grid
                        .params
                        .iter()
                        .map(|a| format!("{}={}:{}:{}", a.name, a.lo, a.hi, a.n))
                        .collect::<Vec<_>>())
                },
            )
            .many(),
            gain_axis("kp", "Kp axis A:B:N (N values from A to B)", "N/rad", |g| &mut g.kp),
            gain_axis("kd", "Kd axis A:B:N", "N s/rad", |g| &mut g.kd),
            Opt::new(
                "ki",
                Kind::Text,
                "N/(rad s)",
                "Ki axis A:B:N (none: Ki = 0, a PD law)",
                |s: &mut SweepSettings, v| {
                    s.grid.ki = if is_none(v) { None } else { Some(axis("ki", v)?) };
                    Ok(())
                },
                |s| s.grid.ki.as_ref().map_or(Value::Null, axis_text),
            ),
            Opt::new(
                "metric",
                Kind::Choice,
                "",
                "What to map: max-lyapunov (λ1 of the nonlinear closed loop's pitch-loop states \
                 after the tilt), spectral-abscissa (largest real part of the linear loop's \
                 poles at the upright) or settling-time (2 % settling time of Φ after the tilt)",
                |s: &mut SweepSettings, v| {
                    s.metric = match as_choice("metric", v, METRICS)? {
                        "max-lyapunov" => Metric::MaxLyapunov,
                        "spectral-abscissa" => Metric::SpectralAbscissa,
                        _ => Metric::SettlingTime,
                    };
                    Ok(())
                },
                |s| json!(s.metric),
            )
            .choices(METRICS),
            optional_vector(
                "x0",
                "SI, rad",
                "Initial model state of the nonlinear metrics (none: at rest with Φ = tilt)",
                field(|s: &mut SweepSettings| &mut s.x0),
            ),
            number(
                "tilt",
                "rad",
                "Initial tilt Φ0 of the nonlinear metrics",
                field(|s: &mut SweepSettings| &mut s.tilt),
            )
            .conflicts(&["x0"]),
        ];
        // The swept gains replace Kp, Ki, Kd: the other controller options only.
        opts.extend(controller(
            one(|s: &mut SweepSettings| &mut s.controller),
            false,
        ));
        let m = field(|s: &mut SweepSettings| &mut s.metric_settings);
        opts.push(number(
            "h",
            "s",
            "RK4 step of the metrics",
            sub(m.clone(), |m| &mut m.h),
        ));
        opts.push(
            number(
                "qr_interval",
                "s",
                "max-lyapunov: re-orthonormalisation interval T",
                sub(m.clone(), |m| &mut m.t_sample),
            )
            .aliases(&["t_sample"]),
        );
        opts.push(integer(
            "iterations",
            "",
            "max-lyapunov: intervals K averaged over",
            sub(m.clone(), |m| &mut m.iterations),
        ));
        opts.push(number(
            "transient",
            "s",
            "max-lyapunov: time discarded before averaging",
            sub(m.clone(), |m| &mut m.transient),
        ));
        opts.push(Opt::new(
            "full_horizon",
            Kind::Flag,
            "",
            "max-lyapunov: step every point to the end of its horizon, without the settled tail \
             (a loop at rest finished from its linearisation, λ1 within 10⁻³ /s)",
            |s: &mut SweepSettings, v| {
                if super::options::as_bool("full_horizon", v)? {
                    if s.metric != Metric::MaxLyapunov {
                        return Err(Error::input(
                            "full_horizon",
                            "applies to metric max-lyapunov only (the other metrics have no \
                             settled tail)",
                        ));
                    }
                    s.metric_settings.settle_distance = None;
                }
                Ok(())
            },
            |s| json!(s.metric_settings.settle_distance.is_none()),
        ));
        opts
    }

    fn validate(s: &SweepSettings) -> Result<()> {
        s.controller.validate()?;
        s.metric_settings.validate()?;
        crate::control::check_tilt("tilt", s.tilt)?;
        Ok(())
    }

    fn budget(model: &ResolvedModel, s: &SweepSettings) -> Result<Budget> {
        let points = s.config(model)?.grid.len() as f64;
        let m = &s.metric_settings;
        let horizon = match s.metric {
            Metric::MaxLyapunov => m.transient + m.t_sample * m.iterations as f64,
            Metric::SettlingTime => m.t_end,
            Metric::SpectralAbscissa => 0.0,
        };
        Ok(Budget {
            horizon,
            steps: points * horizon / m.h,
            points,
            ..Budget::default()
        })
    }

    fn run(
        model: &ResolvedModel,
        s: &SweepSettings,
        progress: &dyn Progress,
    ) -> Result<SweepPoints> {
        sweep(model, s, progress).map(SweepPoints)
    }
}

impl JobOutput for SweepPoints {
    fn summary(&self) -> String {
        format!("{} points: {}\n", self.0.len(), status_counts(&self.0))
    }
}
