//! `phase`: phase portraits (Φ, Φ̇) — the closed loop for several PID gain sets side by side (the
//! study's Fig. 4 a–d), or the open loop under constant inputs.

use std::sync::Arc;

use serde_json::{json, Value};

use super::groups::{controller, gains_json, gains_value, run, Controllers};
use super::options::{as_vector, as_vectors, field, Kind, Opt};
use super::{run_budget, Budget, Job, JobOutput};
use crate::api::{portraits, Drive, PhaseResult, PhaseSettings};
use crate::control::ControllerSettings;
use crate::error::{Error, Result};
use crate::linear::PidGains;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The phase portraits.
pub struct Phase;

/// Gain sets: a list of named gains, or `Kp,Ki,Kd;Kp,Ki,Kd` as text.
fn gain_sets(v: &Value) -> Result<Vec<PidGains>> {
    let sets: Vec<PidGains> = match v {
        Value::String(text) => text
            .split(';')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(|p| gains_value("gains", &Value::String(p.to_string()), PidGains::default()))
            .collect::<Result<_>>()?,
        Value::Array(items) => items
            .iter()
            .map(|g| gains_value("gains", g, PidGains::default()))
            .collect::<Result<_>>()?,
        other => vec![gains_value("gains", other, PidGains::default())?],
    };
    if sets.is_empty() {
        return Err(Error::input(
            "gains",
            "no gain sets (use \"Kp,Ki,Kd;Kp,Ki,Kd\")",
        ));
    }
    Ok(sets)
}

/// Every closed-loop portrait's controller.
fn every_controller() -> Controllers<PhaseSettings> {
    Arc::new(|s, _, apply| {
        let mut any = false;
        for (_, drive) in &mut s.portraits {
            if let Drive::Closed(c) = drive {
                any = true;
                apply(c)?;
            }
        }
        if any {
            Ok(())
        } else {
            Err(Error::input(
                "force",
                "runs the open loop: controller options do not apply",
            ))
        }
    })
}

impl Job for Phase {
    const NAME: &'static str = "phase";
    const FILES: &'static str =
        "phase_1.svg … (one per set), phase.svg (two to a row), their PNGs, phase.csv, phase.json";
    const SUMMARY: &'static str =
        "Phase portraits (Φ, dΦ/dt) for several gain sets side by side (the study's Fig. 4), or \
         open loop under constant inputs";
    type Settings = PhaseSettings;
    type Output = PhaseResult;

    fn options() -> Vec<Opt<PhaseSettings>> {
        let mut opts = vec![
            Opt::new(
                "gains",
                Kind::Text,
                "N/rad, N/(rad s), N s/rad",
                "Gain sets, one portrait each: \"Kp,Ki,Kd;Kp,Ki,Kd;…\" or a list of named gains \
                 (default: the study's Fig. 4 — (a) 3860,1.2e5,1980: Ki above the Routh–Hurwitz \
                 limit, growing oscillation; (b) 3860,3e4,1980: stable, slow oscillation; (c) \
                 1000,0,300: Kp < M_x g, a saddle; (d) 3860,0,1980: the study's PD)",
                |s: &mut PhaseSettings, v| {
                    s.portraits = gain_sets(v)?
                        .into_iter()
                        .map(|g| {
                            // A set of the study's Fig. 4 keeps its panel's name.
                            let label = crate::control::scenario::STUDY_GAIN_SETS
                                .iter()
                                .find(|set| set.gains == g)
                                .map_or_else(
                                    || format!("Kp {} Ki {} Kd {}", g.kp, g.ki, g.kd),
                                    |set| set.label.to_string(),
                                );
                            (label, Drive::Closed(ControllerSettings::pid(g)))
                        })
                        .collect();
                    Ok(())
                },
                |s| {
                    json!(s
                        .portraits
                        .iter()
                        .filter_map(|(_, d)| match d {
                            Drive::Closed(c) => Some(gains_json(&c.pitch.gains)),
                            Drive::Open(_) => None,
                        })
                        .collect::<Vec<_>>())
                },
            ),
            Opt::new(
                "force",
                Kind::Text,
                "N, N m",
                "Open loop instead: constant inputs \"U1,U2;U1,U2;…\" in the model's input order \
                 (F1, T2 for vehicle8/vehicle7; τ_L, τ_R for segway7), one portrait per set",
                |s: &mut PhaseSettings, v| {
                    let sets = as_vectors("force", v)?;
                    if sets.is_empty() {
                        return Err(Error::input("force", "no input sets (use \"F1,T2;F1,T2\")"));
                    }
                    s.portraits = sets
                        .into_iter()
                        .map(|u| {
                            let shown: Vec<String> = u.iter().map(f64::to_string).collect();
                            (
                                format!("open loop, u = ({})", shown.join(",")),
                                Drive::Open(u),
                            )
                        })
                        .collect();
                    Ok(())
                },
                |_| Value::Null,
            )
            .conflicts(&["gains"]),
            Opt::new(
                "x0",
                Kind::Text,
                "SI, rad",
                "Initial states \"x0;x0;…\", each in the model's state order (none: at rest with \
                 Φ = each of tilts)",
                |s: &mut PhaseSettings, v| {
                    s.x0 = if super::options::is_none(v) {
                        None
                    } else {
                        Some(as_vectors("x0", v)?)
                    };
                    Ok(())
                },
                |s| json!(s.x0),
            ),
            Opt::new(
                "tilts",
                Kind::Vector,
                "rad",
                "Initial pitch angles from rest, one run each",
                |s: &mut PhaseSettings, v| {
                    s.tilts = as_vector("tilts", v)?;
                    Ok(())
                },
                |s| json!(s.tilts),
            )
            .conflicts(&["x0"]),
        ];
        opts.extend(controller(every_controller(), false));
        opts.extend(run(field(|s: &mut PhaseSettings| &mut s.run)));
        opts
    }

    fn validate(s: &PhaseSettings) -> Result<()> {
        s.run.validate()?;
        for t in &s.tilts {
            crate::control::check_tilt("tilts", *t)?;
        }
        for (_, drive) in &s.portraits {
            if let Drive::Closed(c) = drive {
                c.validate()?;
            }
        }
        Ok(())
    }

    fn budget(_model: &ResolvedModel, s: &PhaseSettings) -> Result<Budget> {
        let starts = s.x0.as_ref().map_or(s.tilts.len(), Vec::len);
        Ok(run_budget(&s.run, (starts * s.portraits.len()) as f64))
    }

    fn run(
        model: &ResolvedModel,
        s: &PhaseSettings,
        progress: &dyn Progress,
    ) -> Result<PhaseResult> {
        portraits(model, s, progress)
    }
}

impl JobOutput for PhaseResult {
    fn summary(&self) -> String {
        PhaseResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        PhaseResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(PhaseResult::csv(self))
    }
    /// Per portrait and run: Φ0, t, Φ and Φ̇.
    fn series(&self) -> Option<Value> {
        Some(json!(self
            .portraits
            .iter()
            .map(|p| p
                .runs
                .iter()
                .map(|r| json!({
                    "phi0": r.phi0,
                    "t": r.t,
                    "phi": r.points.iter().map(|q| q.0).collect::<Vec<_>>(),
                    "phi_dot": r.points.iter().map(|q| q.1).collect::<Vec<_>>(),
                }))
                .collect::<Vec<_>>())
            .collect::<Vec<_>>()))
    }
}
