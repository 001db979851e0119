//! `twv steer`: balancing a two-wheeler by steering (the Whipple bicycle). At every speed of a
//! range, the lean-and-steer dynamics linearised about straight running ([`SteerLoop`]), the
//! steer-torque law T_δ = k_φ φ + k_δ δ + k_φ̇ φ̇ + k_δ̇ δ̇ either given or tuned to a margin
//! specification with Clarabel (a gain schedule, [`tune_steer`]), its independent certificate
//! (closed-loop eigenvalues, margins at the steer torque), and the nonlinear model steered by
//! it from a push in lean rate ([`ride`]). Each speed's verdict is computed from those numbers.

use std::collections::BTreeMap;

use nalgebra::Complex;
use serde::{Deserialize, Serialize};

use super::ride::{ride, RideSettings, RideVerdict};
use super::steady::modal_plant;
use crate::control::steer::SteerSettings;
use crate::control::RunSettings;
use crate::error::{Error, Result};
use crate::linear::modes::spectral_abscissa;
use crate::linear::steer::{SteerGains, SteerLoop};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::plot::{Curve, Figure, LineChart};
use crate::progress::{Progress, Silent};
use crate::tune::steer::{certify_steer, tune_steer, SteerCertificate, SteerTuneOptions};
use crate::tune::{Spec, TuneStatus};

/// The most speeds one run takes (each is a tuning and a nonlinear run).
pub const MAX_SPEEDS: usize = 1000;

/// Settings of `twv steer`. Defaults beside each field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SteerLoopSettings {
    /// Lowest speed [m/s]. Default 1.
    pub lo: f64,
    /// Highest speed [m/s] (= `lo` for one speed). Default 8.
    pub hi: f64,
    /// Speed step [m/s]. Default 0.5.
    pub step: f64,
    /// Gains to check at every speed; `None` (default): tune a gain schedule to `spec`.
    pub gains: Option<SteerGains>,
    /// The margins every speed must have (and the schedule is tuned to). Default `dpm>=45`.
    pub spec: Spec,
    /// The tuner's options.
    pub options: SteerTuneOptions,
    /// Steer-torque limit in the nonlinear check [N m]; `None` (default): unlimited.
    pub saturation: Option<f64>,
    /// τ [s] of the law's filter on the rates, in the tuning, the certificate and the
    /// nonlinear check alike; `None` (default): unfiltered.
    pub rate_filter: Option<f64>,
    /// The nonlinear check's push: lean rate added to the steady motion [rad/s]. Default 0.5.
    pub push: f64,
    /// Length of the nonlinear check [s]. Default 5.
    pub check_time: f64,
}

impl Default for SteerLoopSettings {
    fn default() -> Self {
        Self {
            lo: 1.0,
            hi: 8.0,
            step: 0.5,
            gains: None,
            spec: "dpm>=45".parse().expect("a valid default spec"),
            options: SteerTuneOptions::default(),
            saturation: None,
            rate_filter: None,
            push: 0.5,
            check_time: 5.0,
        }
    }
}

impl SteerLoopSettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.lo.is_finite() && self.hi.is_finite() && self.hi >= self.lo) {
            return Err(Error::input(
                "speed",
                format!("{}:{} needs finite LO ≤ HI", self.lo, self.hi),
            ));
        }
        if self.lo < 0.0 {
            return Err(Error::input(
                "speed",
                format!(
                    "{} m/s: the steady motion is straight running forward, speeds ≥ 0",
                    self.lo
                ),
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(Error::input(
                "speed",
                format!("step {} must be finite and > 0", self.step),
            ));
        }
        let n = ((self.hi - self.lo) / self.step + 1e-9).floor() + 1.0;
        if n > MAX_SPEEDS as f64 {
            return Err(Error::input(
                "speed",
                format!("{n} speeds is more than {MAX_SPEEDS}"),
            ));
        }
        check_rate_filter(self.rate_filter)?;
        self.law(self.gains.unwrap_or_default()).validate()?;
        crate::tune::steer::validate(&self.options)?;
        crate::tune::steer::check_spec(&self.spec)?;
        if !self.push.is_finite() {
            return Err(Error::input("push", format!("{} is not finite", self.push)));
        }
        if !(self.check_time.is_finite() && self.check_time > 0.0 && self.check_time <= 1e4) {
            return Err(Error::input(
                "check_time",
                format!("{}: a time in (0, 10000] s", self.check_time),
            ));
        }
        Ok(())
    }

    /// The law with `gains` and these settings' limit and filter.
    pub fn law(&self, gains: SteerGains) -> SteerSettings {
        SteerSettings {
            gains,
            saturation: self.saturation,
            rate_filter: self.rate_filter,
        }
    }

    /// The speeds: lo, lo + step, … ≤ hi.
    pub fn speeds(&self) -> Vec<f64> {
        let n = ((self.hi - self.lo) / self.step + 1e-9).floor() as usize + 1;
        (0..n).map(|k| self.lo + k as f64 * self.step).collect()
    }
}

/// The nonlinear model steered from a push at one speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SteeredRide {
    /// Recovered, not recovered or fell (thresholds of `twv ride`); a run whose state blew
    /// up fell.
    pub verdict: RideVerdict,
    /// Largest |φ| [rad] (`None` when the state blew up).
    pub peak: Option<f64>,
    /// |φ| at the end [rad] (`None` when the state blew up).
    pub final_value: Option<f64>,
    /// When the state became non-finite [s] (a loop too stiff for the 1 ms RK4 step, or
    /// unstable), if it did.
    pub diverged_at: Option<f64>,
}

/// One speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerPoint {
    /// The speed [m/s].
    pub speed: f64,
    /// Eigenvalues of the bicycle nobody steers.
    pub open_loop: Vec<Complex<f64>>,
    /// Whether those all have Re < 0.
    pub self_stable: bool,
    /// How the tuning ended (`None` when the gains were given).
    pub tune_status: Option<TuneStatus>,
    /// 1 when met; for an infeasible speed, the largest fraction of the spec met.
    pub best_fraction: f64,
    /// The check of the gains at this speed (`None`: no stabilising gains found).
    pub certificate: Option<SteerCertificate>,
    /// The nonlinear model steered by them from the push.
    pub ride: Option<SteeredRide>,
    /// The spec met and the push recovered from.
    pub met: bool,
}

impl SteerPoint {
    /// The gains used at this speed.
    pub fn gains(&self) -> Option<SteerGains> {
        self.certificate.as_ref().map(|c| c.gains)
    }
}

/// How the run judged the speeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SteerVerdict {
    /// Every speed meets the spec and recovers from the push.
    Met,
    /// Some speed does not (see each point).
    NotMet,
}

/// The result of `twv steer`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerResult {
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// The lean, steer, lean-rate and steer-rate states the gains act on.
    pub modes: Vec<String>,
    /// Whether the gains were tuned (a schedule) or given.
    pub tuned: bool,
    pub spec: Spec,
    pub saturation: Option<f64>,
    /// τ of the law's rate filter [s], `None` when unfiltered.
    pub rate_filter: Option<f64>,
    /// The push [rad/s] and the length [s] of the nonlinear check.
    pub push: f64,
    pub check_time: f64,
    pub points: Vec<SteerPoint>,
    /// The largest change of the gains between neighbouring speeds that both have gains,
    /// relative to their size (the schedule's continuity; 0 for given gains).
    pub largest_step: f64,
    pub verdict: SteerVerdict,
}

/// The nonlinear check at one speed.
fn steered_ride(
    model: &ResolvedModel,
    s: &SteerLoopSettings,
    modes: &[String],
    speed: f64,
    gains: SteerGains,
) -> Result<SteeredRide> {
    let settings = RideSettings {
        speed: Some(speed),
        perturb: BTreeMap::from([(modes[2].clone(), s.push)]),
        steer: Some(s.law(gains)),
        watch: modes[0].clone(),
        run: RunSettings {
            t_end: s.check_time,
            ..RunSettings::default()
        },
        ..RideSettings::default()
    };
    use crate::control::ControlError;
    use crate::integrate::IntegrateError;
    match ride(model, &settings, &Silent) {
        Ok(r) => Ok(SteeredRide {
            verdict: r.verdict,
            peak: Some(r.peak),
            final_value: Some(r.final_value),
            diverged_at: None,
        }),
        Err(Error::Control(ControlError::Integrate(IntegrateError::BlowUp { t, .. })))
        | Err(Error::Integrate(IntegrateError::BlowUp { t, .. })) => Ok(SteeredRide {
            verdict: RideVerdict::Fell,
            peak: None,
            final_value: None,
            diverged_at: Some(t),
        }),
        Err(other) => Err(other),
    }
}

/// The index of `model`'s steer-torque input, or why it has none.
pub fn steer_input(model: &ResolvedModel) -> Result<usize> {
    crate::control::steer::steer_input(model.name(), &model.inputs())
}

/// The steer loop of `model` at `speed`.
pub fn steer_loop(model: &ResolvedModel, speed: f64) -> Result<SteerLoop> {
    let input = steer_input(model)?;
    let plant = modal_plant(model, speed)?;
    SteerLoop::new(speed, plant.modes, plant.a, &plant.b, input).map_err(|e| Error::Unsupported {
        model: model.name().to_string(),
        reason: format!("its steady motion is not a lean-and-steer plant: {e}"),
    })
}

/// Runs `twv steer`.
pub fn steer(
    model: &ResolvedModel,
    s: &SteerLoopSettings,
    progress: &dyn Progress,
) -> Result<SteerResult> {
    s.validate()?;
    let speeds = s.speeds();
    progress.start(speeds.len() as u64, "speeds");
    let stop = || progress.cancelled();
    let mut points = Vec::with_capacity(speeds.len());
    let mut modes = Vec::new();
    for v in speeds {
        if progress.cancelled() {
            return Err(Error::Interrupted);
        }
        let lp = steer_loop(model, v)?.with_rate_filter(s.rate_filter)?;
        modes = lp.modes().to_vec();
        let open_loop = lp.open_loop_eigenvalues()?;
        let (tune_status, best_fraction, certificate) = match s.gains {
            Some(g) => {
                let c = certify_steer(&lp, &g, &s.spec)?;
                let fraction = if c.meets_spec { 1.0 } else { 0.0 };
                (None, fraction, Some(c))
            }
            None => {
                let t = tune_steer(&lp, &s.spec, &s.options, &stop)?;
                (Some(t.status), t.best_fraction, t.certificate)
            }
        };
        let gains = certificate.as_ref().map(|c| c.gains);
        let ride = match gains {
            Some(g) => Some(steered_ride(model, s, &modes, v, g)?),
            None => None,
        };
        let met = certificate.as_ref().is_some_and(|c| c.meets_spec)
            && ride.is_some_and(|r| r.verdict == RideVerdict::Recovered);
        points.push(SteerPoint {
            speed: v,
            self_stable: spectral_abscissa(&open_loop) < 0.0,
            open_loop,
            tune_status,
            best_fraction,
            certificate,
            ride,
            met,
        });
        progress.advance(1);
    }
    let largest_step = points
        .windows(2)
        .filter_map(|w| {
            let (a, b) = (w[0].gains()?.row(), w[1].gains()?.row());
            let diff = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
            let size = a.iter().chain(&b).map(|x| x * x).sum::<f64>() / 2.0;
            (size > 0.0).then(|| (diff / size).sqrt())
        })
        .fold(0.0, f64::max);
    Ok(SteerResult {
        model: model.name().to_string(),
        params: model.params_origin.clone(),
        modes,
        tuned: s.gains.is_none(),
        spec: s.spec.clone(),
        saturation: s.saturation,
        rate_filter: s.rate_filter,
        push: s.push,
        check_time: s.check_time,
        verdict: if points.iter().all(|p| p.met) {
            SteerVerdict::Met
        } else {
            SteerVerdict::NotMet
        },
        largest_step,
        points,
    })
}

/// Refuses a rate filter that is not a time constant in (0, MAX_RATE_FILTER] s, naming the
/// option `rate_filter`.
pub(super) fn check_rate_filter(tau: Option<f64>) -> Result<()> {
    SteerSettings {
        rate_filter: tau,
        ..SteerSettings::default()
    }
    .validate()
    .map_err(|e| match e {
        Error::Input { reason, .. } => Error::input("rate_filter", reason),
        other => other,
    })
}

/// Refuses non-finite steer gains, naming the option `gains` and the gain.
pub(super) fn finite_gains(g: &SteerGains) -> Result<()> {
    for (name, k) in SteerGains::NAMES.iter().zip(g.row()) {
        if !k.is_finite() {
            return Err(Error::input("gains", format!("{name} = {k} is not finite")));
        }
    }
    Ok(())
}

/// `x` or an empty CSV field (the steer results' CSVs).
pub(super) fn csv_field(x: Option<f64>) -> String {
    x.map_or(String::new(), |v| format!("{v}"))
}

impl SteerResult {
    /// One row per speed.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "speed,self_stable,status,k_phi,k_delta,k_phi_dot,k_delta_dot,\
             open_loop_abscissa,closed_loop_abscissa,disk_phase_margin_deg,disk_gain_margin,\
             peak_sensitivity,ride,peak_lean,met\n",
        );
        for p in &self.points {
            let c = p.certificate.as_ref();
            let k = p.gains().map(|g| g.row());
            let status = match (p.tune_status, c) {
                (Some(t), _) => format!("{t:?}"),
                (None, Some(c)) if c.meets_spec => "given, meets spec".into(),
                (None, _) => "given, does not meet spec".into(),
            };
            let row = [
                format!("{}", p.speed),
                format!("{}", p.self_stable),
                status,
                csv_field(k.map(|k| k[0])),
                csv_field(k.map(|k| k[1])),
                csv_field(k.map(|k| k[2])),
                csv_field(k.map(|k| k[3])),
                format!("{}", spectral_abscissa(&p.open_loop)),
                csv_field(c.map(|c| c.analysis.closed_loop.spectral_abscissa)),
                csv_field(c.map(|c| c.analysis.margins.disk.phase_deg)),
                csv_field(c.map(|c| c.analysis.margins.disk.gain_high)),
                csv_field(c.map(|c| c.analysis.margins.peak_sensitivity)),
                p.ride.map_or(String::new(), |r| match r.diverged_at {
                    Some(t) => format!("diverged at {t} s"),
                    None => format!("{:?}", r.verdict),
                }),
                csv_field(p.ride.and_then(|r| r.peak)),
                format!("{}", p.met),
            ];
            out += &(row.join(",") + "\n");
        }
        out
    }

    /// The schedule's gains, the spectral abscissa open and closed, and the disk phase margin,
    /// against speed.
    pub fn figures(&self) -> Vec<(String, Figure)> {
        let series = |f: &dyn Fn(&SteerPoint) -> Option<f64>| -> Vec<(f64, f64)> {
            self.points
                .iter()
                .filter_map(|p| Some((p.speed, f(p)?)))
                .collect()
        };
        let what = if self.tuned {
            "tuned to"
        } else {
            "checked against"
        };
        let gains = SteerGains::NAMES
            .iter()
            .enumerate()
            .map(|(j, name)| Curve {
                name: name.to_string(),
                points: series(&|p| Some(p.gains()?.row()[j])),
            })
            .collect();
        let abscissa = vec![
            Curve {
                name: "nobody steers".into(),
                points: series(&|p| Some(spectral_abscissa(&p.open_loop))),
            },
            Curve {
                name: "steered".into(),
                points: series(&|p| {
                    Some(
                        p.certificate
                            .as_ref()?
                            .analysis
                            .closed_loop
                            .spectral_abscissa,
                    )
                }),
            },
        ];
        let margin = vec![Curve {
            name: "disk phase margin".into(),
            points: series(&|p| {
                let m = &p.certificate.as_ref()?.analysis.margins;
                (m.stable && m.disk.phase_deg.is_finite()).then_some(m.disk.phase_deg)
            }),
        }];
        vec![
            (
                "gains.svg".into(),
                Figure::Line(LineChart::new(
                    &format!("{} steer gains, {what} {}", self.model, self.spec),
                    "speed [m/s]",
                    "gain [N m/rad, N m s/rad]",
                    (800, 450),
                    gains,
                )),
            ),
            (
                "abscissa.svg".into(),
                Figure::Line(LineChart::new(
                    &format!("{}: largest real part of the eigenvalues", self.model),
                    "speed [m/s]",
                    "max Re λ [1/s]",
                    (800, 450),
                    abscissa,
                )),
            ),
            (
                "margins.svg".into(),
                Figure::Line(LineChart::new(
                    &format!("{}: disk phase margin at the steer torque", self.model),
                    "speed [m/s]",
                    "disk phase margin [deg]",
                    (800, 450),
                    margin,
                )),
            ),
        ]
    }

    /// steer.csv, steer.json and the figures (SVG and PNG).
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.text("steer.csv", self.csv());
        f.json("steer.json", self);
        for (name, figure) in self.figures() {
            f.figure(&name, &figure)?;
        }
        Ok(f)
    }

    /// A few readable lines: what was asked, at how many speeds it was met, which were not and
    /// why, with the thresholds.
    pub fn summary(&self) -> String {
        let n = self.points.len();
        let met = self.points.iter().filter(|p| p.met).count();
        let (lo, hi) = (
            self.points.first().map_or(f64::NAN, |p| p.speed),
            self.points.last().map_or(f64::NAN, |p| p.speed),
        );
        let speeds = if n == 1 {
            format!("at {lo} m/s")
        } else {
            format!("at {n} speeds {lo}–{hi} m/s")
        };
        let mut out = format!(
            "{} steered, {} {} {speeds} ({}): met at {met} of {n}\n",
            self.model,
            if self.tuned {
                "gains tuned to"
            } else {
                "given gains checked against"
            },
            self.spec,
            self.params,
        );
        out += &format!(
            "  met = the certificate meets the spec (closed-loop eigenvalues Re < 0, margins at \
             the steer torque) and the nonlinear model recovers from a {} rad/s push in {} \
             within {} s (|{}| over the last 10 % ≤ 0.1 × its peak)\n",
            self.push,
            self.modes.get(2).map_or("the lean rate", String::as_str),
            self.check_time,
            self.modes.first().map_or("lean", String::as_str),
        );
        if let Some(tau) = self.rate_filter {
            out += &format!(
                "  the law reads the rates through 1/({tau} s · s + 1) in the tuning, the \
                 certificates and the nonlinear check\n"
            );
        }
        for p in self.points.iter().filter(|p| !p.met) {
            let why = match (&p.certificate, p.ride) {
                (None, _) => "no stabilising gains found".to_string(),
                (Some(c), _) if !c.meets_spec && p.tune_status.is_some() => format!(
                    "infeasible: best {:.0} % of the spec (disk phase margin {:.1}°)",
                    100.0 * p.best_fraction,
                    c.analysis.margins.disk.phase_deg
                ),
                (Some(c), _) if !c.meets_spec => format!(
                    "does not meet the spec (stable: {}, disk phase margin {:.1}°)",
                    c.analysis.closed_loop.stable, c.analysis.margins.disk.phase_deg
                ),
                (Some(_), Some(r)) => match r.diverged_at {
                    Some(t) => format!(
                        "the nonlinear check diverged at t = {t:.3} s (the state became \
                         non-finite: a loop too stiff for the 1 ms RK4 step, or unstable)"
                    ),
                    None => format!("the nonlinear check: {:?}", r.verdict),
                },
                (Some(_), None) => "no nonlinear check".to_string(),
            };
            out += &format!("  {} m/s: {why}\n", p.speed);
        }
        if self.tuned && met > 1 {
            out += &format!(
                "  largest change of the gains between neighbouring speeds: {:.0} % of their \
                 size\n",
                100.0 * self.largest_step
            );
        }
        out
    }
}
