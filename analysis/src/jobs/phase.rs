//! `phase`: phase portraits (Φ, Φ̇) — the closed loop for several PID gain sets side by side (the
//! study's Fig. 4 a–d), or the open loop under constant inputs.

use std::sync::Arc;

use serde_json::{json, Value};

use super::groups::{
    controller, gains_json, gains_value, run, steer_gains_json, steer_gains_value, Controllers,
};
use super::options::{as_vector, as_vectors, field, optional_number, Kind, Opt};
use super::{run_budget, Budget, Job, JobOutput};
use crate::api::{portraits, Drive, PhaseResult, PhaseSettings};
use crate::control::steer::SteerSettings;
use crate::control::ControllerSettings;
use crate::error::{Error, Result};
use crate::linear::{PidGains, SteerGains};
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
/// Steer gain sets: "k_phi=…,k_phi_dot=…;k_phi=…" or a list of named gains (each set's
/// missing gains 0).
fn steer_sets(v: &Value) -> Result<Vec<SteerGains>> {
    let one = |g: &Value| steer_gains_value("steer_gains", g, SteerGains::default());
    let sets: Vec<SteerGains> = match v {
        Value::String(text) => text
            .split(';')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(|p| one(&Value::String(p.to_string())))
            .collect::<Result<_>>()?,
        Value::Array(items) => items.iter().map(one).collect::<Result<_>>()?,
        other => vec![one(other)?],
    };
    if sets.is_empty() {
        return Err(Error::input(
            "steer_gains",
            "no steer gain sets (use \"k_phi=…,k_phi_dot=…;k_phi=…\")",
        ));
    }
    Ok(sets)
}

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
                            Drive::Open(_) | Drive::Steer(_) => None,
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
                "steer_gains",
                Kind::Text,
                "N m/rad, N m s/rad",
                "Steer laws instead, one portrait each, for a two-wheeler with a steer input \
                 (whipple, with --speed): T_delta = k_phi φ + k_delta δ + k_phi_dot φ̇ + \
                 k_delta_dot δ̇, \"k_phi=…,k_phi_dot=…;k_phi=…\" (a set's missing gains 0)",
                |s: &mut PhaseSettings, v| {
                    s.portraits = steer_sets(v)?
                        .into_iter()
                        .map(|g| {
                            let label = format!(
                                "k_phi {} k_delta {} k_phi_dot {} k_delta_dot {}",
                                g.k_phi, g.k_delta, g.k_phi_dot, g.k_delta_dot
                            );
                            (label, Drive::Steer(SteerSettings::gains(g)))
                        })
                        .collect();
                    Ok(())
                },
                |s| {
                    let sets: Vec<Value> = s
                        .portraits
                        .iter()
                        .filter_map(|(_, d)| match d {
                            Drive::Steer(law) => Some(steer_gains_json(&law.gains)),
                            _ => None,
                        })
                        .collect();
                    if sets.is_empty() {
                        Value::Null
                    } else {
                        json!(sets)
                    }
                },
            )
            .conflicts(&["gains", "force"]),
            optional_number(
                "speed",
                "m/s",
                "Start from the model's steady motion at this speed, leaning by each of --tilts \
                 (models whose IR describes one, e.g. whipple); needed by --steer-gains",
                field(|s: &mut PhaseSettings| &mut s.speed),
            )
            .conflicts(&["x0"]),
            optional_number(
                "steer_filter",
                "s",
                "Time constant τ of a first-order filter on the lean and steer rates every steer \
                 law reads, 1/(τs + 1) (none: read directly); with --steer-gains",
                field(|s: &mut PhaseSettings| &mut s.steer_filter),
            ),
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
                "Initial pitch angles from rest (leans from the steady motion with --speed), one \
                 run each",
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
            match drive {
                Drive::Closed(c) => c.validate()?,
                Drive::Steer(law) => law.validate()?,
                Drive::Open(_) => {}
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
