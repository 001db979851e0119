//! `twv steer-map`: where a steer-torque law balances a two-wheeler — the largest real part of
//! the closed loop's eigenvalues (the vehicle maps' spectral abscissa) over speed × one steer
//! gain, the other gains fixed, with the speeds at which nobody needs to steer (the open loop's
//! self-stable band, from [`steady_motion`]) marked. Each cell is the 4 × 4 lean-and-steer loop
//! of [`steer_loop`] at that speed closed by those gains: linear, exact, microseconds a cell,
//! so a 1000 × 1000 map needs no cluster.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::steady::{steady_motion, SteadySettings};
use super::steer::{check_rate_filter, csv_field, finite_gains, steer_loop};
use crate::error::{Error, Result};
use crate::linear::SteerGains;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::plot::{Figure, HeatMap, Mark};
use crate::progress::{Progress, Silent};
use crate::sweep::Axis;

/// The most speeds, and the most values of the gain, of one map.
pub const MAX_AXIS: usize = 1000;

/// The speed step of the open-loop band's search [m/s]: its bounds are then refined to
/// [`SteadySettings`]' tolerance (1e-13 m/s), so the step only has to be finer than the band
/// (1.7 m/s wide for the benchmark bicycle, 0.8–2.5 m/s for the measured ones).
pub(super) const BAND_STEP: f64 = 0.05;

/// Settings of `twv steer-map`. Defaults beside each field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SteerMapSettings {
    /// Speeds [m/s]. Default 0.5:10:96 (every 0.1 m/s).
    pub speed: Axis,
    /// The gain the map varies: `k_phi`, `k_delta`, `k_phi_dot` or `k_delta_dot`. Default
    /// `k_phi_dot`, the lean-rate feedback of steering into the fall.
    pub gain: String,
    /// Its values [N m/rad or N m s/rad]. Default −20:60:81.
    pub values: Axis,
    /// The other gains (the varied gain's entry is ignored). Default all 0.
    pub gains: SteerGains,
    /// τ of the law's filter on the rates [s]; `None` (default): unfiltered.
    pub rate_filter: Option<f64>,
}

impl Default for SteerMapSettings {
    fn default() -> Self {
        Self {
            speed: Axis {
                lo: 0.5,
                hi: 10.0,
                n: 96,
            },
            gain: "k_phi_dot".into(),
            values: Axis {
                lo: -20.0,
                hi: 60.0,
                n: 81,
            },
            gains: SteerGains::default(),
            rate_filter: None,
        }
    }
}

impl SteerMapSettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        for (name, a) in [("speed", &self.speed), ("values", &self.values)] {
            if !(a.lo.is_finite() && a.hi.is_finite()) {
                return Err(Error::input(
                    name,
                    format!("{}:{} must be finite", a.lo, a.hi),
                ));
            }
            if a.n == 0 || a.n > MAX_AXIS {
                return Err(Error::input(
                    name,
                    format!("{} values: from 1 to {MAX_AXIS}", a.n),
                ));
            }
            if a.n > 1 && a.hi <= a.lo {
                return Err(Error::input(
                    name,
                    format!("{}:{}:{} needs LO < HI for N > 1", a.lo, a.hi, a.n),
                ));
            }
        }
        if self.speed.lo < 0.0 {
            return Err(Error::input(
                "speed",
                format!(
                    "{} m/s: the steady motion is straight running forward, speeds ≥ 0",
                    self.speed.lo
                ),
            ));
        }
        self.gain_index()?;
        finite_gains(&self.gains)?;
        check_rate_filter(self.rate_filter)
    }

    /// The varied gain's position in [`SteerGains::NAMES`].
    fn gain_index(&self) -> Result<usize> {
        SteerGains::NAMES
            .iter()
            .position(|n| *n == self.gain)
            .ok_or_else(|| {
                Error::input(
                    "gain",
                    format!(
                        "`{}` is not a steer gain; the gains are {}",
                        self.gain,
                        SteerGains::NAMES.join(", ")
                    ),
                )
            })
    }
}

/// How the map came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SteerMapVerdict {
    /// Some cell's closed loop is stable.
    StableSomewhere,
    /// No value of the gain stabilises the loop at any speed of the map.
    NowhereStable,
}

/// The values of the gain that stabilise the loop at one speed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StabilisingRange {
    /// The speed [m/s].
    pub speed: f64,
    /// The smallest and largest stabilising value on the map's grid (`None`: none does).
    pub lo: Option<f64>,
    pub hi: Option<f64>,
    /// How many of the map's values stabilise.
    pub count: usize,
}

/// The result of `twv steer-map`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerMapResult {
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// The lean, steer, lean-rate and steer-rate states the gains act on.
    pub modes: Vec<String>,
    /// The varied gain, and the others.
    pub gain: String,
    pub gains: SteerGains,
    pub speeds: Vec<f64>,
    pub values: Vec<f64>,
    /// max Re λ of the closed loop [1/s], row-major over (values, speeds): entry
    /// `j · speeds.len() + i` is at (`speeds[i]`, `values[j]`); `None` where the eigenvalues are
    /// not finite (gains too large for double precision).
    pub abscissa: Vec<Option<f64>>,
    /// Per speed, the values of the gain that stabilise.
    pub stabilising: Vec<StabilisingRange>,
    /// Nobody steering: the speed intervals of the map's range where the bicycle is
    /// self-stable, and its weave and capsize speeds there (`None`: not within the range, or
    /// the map has one speed).
    pub self_stable: Vec<(f64, f64)>,
    pub weave_speed: Option<f64>,
    pub capsize_speed: Option<f64>,
    /// Stable cells out of all.
    pub stable_cells: usize,
    pub verdict: SteerMapVerdict,
}

/// Runs `twv steer-map`.
pub fn steer_map(
    model: &ResolvedModel,
    s: &SteerMapSettings,
    progress: &dyn Progress,
) -> Result<SteerMapResult> {
    s.validate()?;
    let j = s.gain_index()?;
    let (speeds, values) = (s.speed.values(), s.values.values());
    progress.start(speeds.len() as u64, "speeds");
    // One column per speed, the speeds over rayon's threads (each column's cells are
    // independent of the order: same bytes on any number of threads).
    let columns: Vec<(Vec<String>, Vec<Option<f64>>)> = speeds
        .par_iter()
        .map(|&v| {
            if progress.cancelled() {
                return Err(Error::Interrupted);
            }
            let lp = steer_loop(model, v)?.with_rate_filter(s.rate_filter)?;
            let column = values
                .iter()
                .map(|&x| {
                    let mut row = s.gains.row();
                    row[j] = x;
                    lp.closed_loop_abscissa(&SteerGains::from_row(row))
                })
                .collect();
            progress.advance(1);
            Ok((lp.modes().to_vec(), column))
        })
        .collect::<Result<_>>()?;
    let modes = columns.first().map_or(Vec::new(), |c| c.0.clone());
    let columns: Vec<Vec<Option<f64>>> = columns.into_iter().map(|c| c.1).collect();
    let abscissa: Vec<Option<f64>> = (0..values.len())
        .flat_map(|jv| columns.iter().map(move |c| c[jv]))
        .collect();
    let stable = |a: &Option<f64>| a.is_some_and(|a| a < 0.0);
    let stabilising = speeds
        .iter()
        .zip(&columns)
        .map(|(&speed, column)| {
            let ok: Vec<f64> = values
                .iter()
                .zip(column)
                .filter(|(_, a)| stable(a))
                .map(|(x, _)| *x)
                .collect();
            StabilisingRange {
                speed,
                lo: ok.first().copied(),
                hi: ok.last().copied(),
                count: ok.len(),
            }
        })
        .collect();
    let band = (s.speed.n > 1)
        .then(|| {
            steady_motion(
                model,
                &SteadySettings {
                    lo: s.speed.lo,
                    hi: s.speed.hi,
                    step: BAND_STEP.min((s.speed.hi - s.speed.lo) / 10.0),
                    ..SteadySettings::default()
                },
                &Silent,
            )
        })
        .transpose()?;
    let stable_cells = abscissa.iter().filter(|a| stable(a)).count();
    Ok(SteerMapResult {
        model: model.name().to_string(),
        params: model.params_origin.clone(),
        modes,
        gain: s.gain.clone(),
        gains: s.gains,
        speeds,
        values,
        abscissa,
        stabilising,
        self_stable: band
            .as_ref()
            .map_or(Vec::new(), |b| b.stable_ranges.clone()),
        weave_speed: band.as_ref().and_then(|b| b.weave_speed),
        capsize_speed: band.as_ref().and_then(|b| b.capsize_speed),
        stable_cells,
        verdict: if stable_cells > 0 {
            SteerMapVerdict::StableSomewhere
        } else {
            SteerMapVerdict::NowhereStable
        },
    })
}

/// A grid value as a person writes it: `0.9`, not the `0.8999999999999999` that evenly spaced
/// values computed from their index can be (1e-9 is far below any speed or gain's meaning).
fn short(x: f64) -> String {
    format!("{}", (x * 1e9).round() / 1e9)
}

impl SteerMapResult {
    /// The varied gain's unit.
    fn unit(&self) -> &'static str {
        if self.gain.ends_with("_dot") {
            "N m s/rad"
        } else {
            "N m/rad"
        }
    }

    /// The other gains, as `k=v` (only those not 0).
    fn others(&self) -> String {
        let row = self.gains.row();
        let set: Vec<String> = SteerGains::NAMES
            .iter()
            .zip(row)
            .filter(|(n, v)| **n != self.gain && *v != 0.0)
            .map(|(n, v)| format!("{n}={v}"))
            .collect();
        if set.is_empty() {
            "the other gains 0".into()
        } else {
            format!("the other gains {}", set.join(", "))
        }
    }

    /// One row per cell: speed, gain value, abscissa (empty where none), stable.
    pub fn csv(&self) -> String {
        let mut out = format!("speed,{},closed_loop_abscissa,stable\n", self.gain);
        let n = self.speeds.len();
        for (jv, x) in self.values.iter().enumerate() {
            for (i, v) in self.speeds.iter().enumerate() {
                let a = self.abscissa[jv * n + i];
                out += &format!("{v},{x},{},{}\n", csv_field(a), a.is_some_and(|a| a < 0.0));
            }
        }
        out
    }

    /// The map: abscissa over (speed, gain) with the stability boundary, and the weave and
    /// capsize speeds marked.
    pub fn figure(&self) -> Figure {
        let values: Vec<f64> = self
            .abscissa
            .iter()
            .map(|a| a.unwrap_or(f64::NAN))
            .collect();
        let mut marks = Vec::new();
        if let Some(w) = self.weave_speed {
            marks.push(Mark {
                x: w,
                label: format!(" weave {w:.2}"),
            });
        }
        if let Some(c) = self.capsize_speed {
            marks.push(Mark {
                x: c,
                label: format!(" capsize {c:.2}"),
            });
        }
        Figure::Heat(HeatMap {
            title: format!(
                "{} steered by {} ({})",
                self.model,
                self.gain,
                self.others()
            ),
            x_label: "speed v [m/s]".into(),
            y_label: format!("{} [{}]", self.gain, self.unit()),
            value_label: "max Re λ of the closed loop [1/s]".into(),
            xs: self.speeds.clone(),
            ys: self.values.clone(),
            missing: self
                .abscissa
                .iter()
                .map(|a| a.is_none().then_some("failed"))
                .collect(),
            boundary: values.clone(),
            values,
            signed: true,
            marks,
            size: (960, 700),
        })
    }

    /// steer_map.csv, steer_map.json and map.svg (and PNG).
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.text("steer_map.csv", self.csv());
        f.json("steer_map.json", self);
        f.figure("map.svg", &self.figure())?;
        Ok(f)
    }

    /// What was mapped, how much of it is stable, where some value stabilises, and the band
    /// where nobody needs to steer.
    pub fn summary(&self) -> String {
        let (n, m) = (self.speeds.len(), self.values.len());
        let span = |xs: &[f64]| match (xs.first(), xs.last()) {
            (Some(a), Some(b)) if a != b => format!("{} to {}", short(*a), short(*b)),
            (Some(a), _) => short(*a),
            _ => String::new(),
        };
        let mut out = format!(
            "{} steered by {} over {n} speeds {} m/s × {m} values {} {} ({}; {}): stable \
             (max Re λ < 0) in {} of {} cells\n",
            self.model,
            self.gain,
            span(&self.speeds),
            span(&self.values),
            self.unit(),
            self.others(),
            self.params,
            self.stable_cells,
            n * m
        );
        let helped: Vec<f64> = self
            .stabilising
            .iter()
            .filter(|r| r.count > 0)
            .map(|r| r.speed)
            .collect();
        out += &match (helped.first(), helped.last()) {
            (Some(a), Some(b)) => format!(
                "  some value of {} stabilises it at {} of {n} speeds, from {} to {} m/s\n",
                self.gain,
                helped.len(),
                short(*a),
                short(*b)
            ),
            _ => format!(
                "  no value of {} on the map stabilises it at any speed\n",
                self.gain
            ),
        };
        out += &if self.self_stable.is_empty() {
            "  nobody steering, it is self-stable at no speed of the map\n".to_string()
        } else {
            let bands: Vec<String> = self
                .self_stable
                .iter()
                .map(|(a, b)| format!("{a:.4}–{b:.4}"))
                .collect();
            format!(
                "  nobody steering, it is self-stable at {} m/s (dashed lines on the map)\n",
                bands.join(", ")
            )
        };
        out
    }
}
