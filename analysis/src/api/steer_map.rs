//! `twv steer-map`: where a steer-torque law balances a two-wheeler — the largest real part of
//! the closed loop's eigenvalues (the vehicle maps' spectral abscissa) over speed × one steer
//! gain, the other gains fixed, with the speeds at which nobody needs to steer (the open loop's
//! self-stable band, from [`steady_motion`]) marked; or, at one speed, over one steer gain ×
//! another (`against`). Each cell is the 4 × 4 lean-and-steer loop of [`steer_loop`] at that
//! speed closed by those gains: linear, exact, microseconds a cell, so a 1000 × 1000 map needs
//! no cluster.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::steady::{steady_motion, SteadySettings};
use super::steer::{check_rate_filter, csv_field, finite_gains, steer_loop};
use crate::error::{Error, Result};
use crate::linear::{SteerGains, SteerLoop};
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
    /// Speeds [m/s]. Default 0.5:10:96 (every 0.1 m/s); one speed with `against`.
    pub speed: Axis,
    /// The gain the map varies: `k_phi`, `k_delta`, `k_phi_dot` or `k_delta_dot`. Default
    /// `k_phi_dot`, the lean-rate feedback of steering into the fall.
    pub gain: String,
    /// Its values [N m/rad or N m s/rad]. Default −20:60:81.
    pub values: Axis,
    /// A second gain for the map's x axis instead of speed: a gain × gain map at the one speed
    /// of `speed`. Default `None` (the x axis is speed).
    pub against: Option<String>,
    /// Its values [N m/rad or N m s/rad]. Default −20:60:81.
    pub against_values: Axis,
    /// The other gains (the varied gains' entries are ignored). Default all 0.
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
            against: None,
            against_values: Axis {
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
        for (name, a) in [
            ("speed", &self.speed),
            ("values", &self.values),
            ("against_values", &self.against_values),
        ] {
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
        if let Some(against) = &self.against {
            gain_index("against", against)?;
            if *against == self.gain {
                return Err(Error::input(
                    "against",
                    format!("`{against}` is the map's gain already; choose another steer gain"),
                ));
            }
            if self.speed.n != 1 {
                return Err(Error::input(
                    "speed",
                    format!(
                        "{} speeds: a gain × gain map (against {against}) is at one speed, \
                         e.g. 3",
                        self.speed.n
                    ),
                ));
            }
        }
        finite_gains(&self.gains)?;
        check_rate_filter(self.rate_filter)
    }

    /// The varied gain's position in [`SteerGains::NAMES`].
    fn gain_index(&self) -> Result<usize> {
        gain_index("gain", &self.gain)
    }
}

/// `gain`'s position in [`SteerGains::NAMES`]; the error names `field`.
fn gain_index(field: &str, gain: &str) -> Result<usize> {
    SteerGains::NAMES
        .iter()
        .position(|n| *n == gain)
        .ok_or_else(|| {
            Error::input(
                field,
                format!(
                    "`{gain}` is not a steer gain; the gains are {}",
                    SteerGains::NAMES.join(", ")
                ),
            )
        })
}

/// How the map came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SteerMapVerdict {
    /// Some cell's closed loop is stable.
    StableSomewhere,
    /// No cell of the map stabilises the loop.
    NowhereStable,
}

/// The values of the gain that stabilise the loop in one column of the map: at one speed, or
/// at one value of the second gain.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StabilisingRange {
    /// The speed [m/s].
    pub speed: f64,
    /// The second gain's value in a gain × gain map (`None` in a speed × gain map).
    pub against: Option<f64>,
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
    /// The second gain of a gain × gain map and its values (the map's x axis, at the one speed
    /// of `speeds`); `None` and empty in a speed × gain map.
    pub against: Option<String>,
    pub against_values: Vec<f64>,
    /// max Re λ of the closed loop [1/s], row-major over (values, x) where x is `speeds`, or
    /// `against_values` in a gain × gain map: entry `j · x.len() + i` is at (`x[i]`,
    /// `values[j]`); `None` where the eigenvalues are not finite (gains too large for double
    /// precision).
    pub abscissa: Vec<Option<f64>>,
    /// Per column (speed, or value of the second gain), the values of the gain that stabilise.
    pub stabilising: Vec<StabilisingRange>,
    /// The open loop's max Re λ [1/s] when the map has one speed (nobody steering; a map over
    /// speeds has its self-stable band instead).
    pub unsteered_abscissa: Option<f64>,
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
    let k = s
        .against
        .as_deref()
        .map(|a| gain_index("against", a))
        .transpose()?;
    let (speeds, values) = (s.speed.values(), s.values.values());
    let against_values = if k.is_some() {
        s.against_values.values()
    } else {
        Vec::new()
    };
    let closed = |v: f64| -> Result<SteerLoop> {
        Ok(steer_loop(model, v)?.with_rate_filter(s.rate_filter)?)
    };
    // One column of cells: the varied gain's values, the second gain (if any) at `x`.
    let column = |lp: &SteerLoop, x: Option<f64>| -> Vec<Option<f64>> {
        values
            .iter()
            .map(|&y| {
                let mut row = s.gains.row();
                row[j] = y;
                if let (Some(k), Some(x)) = (k, x) {
                    row[k] = x;
                }
                lp.closed_loop_abscissa(&SteerGains::from_row(row))
            })
            .collect()
    };
    // The map's columns: (speed, the second gain's value) of each. A map at one speed (every
    // gain × gain map) closes one loop for all of them, a map over speeds one per speed.
    let at: Vec<(f64, Option<f64>)> = match k {
        Some(_) => against_values
            .iter()
            .map(|&x| (speeds[0], Some(x)))
            .collect(),
        None => speeds.iter().map(|&v| (v, None)).collect(),
    };
    let shared = match speeds[..] {
        [v] => Some(closed(v)?),
        _ => None,
    };
    progress.start(
        at.len() as u64,
        if k.is_some() { "values" } else { "speeds" },
    );
    // The columns over rayon's threads (each column's cells are independent of the order: same
    // bytes on any number of threads).
    let built: Vec<(Vec<String>, Vec<Option<f64>>)> = at
        .par_iter()
        .map(|&(v, x)| {
            if progress.cancelled() {
                return Err(Error::Interrupted);
            }
            let own;
            let lp = match &shared {
                Some(lp) => lp,
                None => {
                    own = closed(v)?;
                    &own
                }
            };
            let c = column(lp, x);
            progress.advance(1);
            Ok((lp.modes().to_vec(), c))
        })
        .collect::<Result<_>>()?;
    let modes = built.first().map_or(Vec::new(), |c| c.0.clone());
    let columns: Vec<Vec<Option<f64>>> = built.into_iter().map(|c| c.1).collect();
    // At one speed, the open loop's own verdict (no band to search for).
    let unsteered_abscissa = shared
        .as_ref()
        .and_then(|lp| lp.closed_loop_abscissa(&SteerGains::default()));
    let abscissa: Vec<Option<f64>> = (0..values.len())
        .flat_map(|jv| columns.iter().map(move |c| c[jv]))
        .collect();
    let stable = |a: &Option<f64>| a.is_some_and(|a| a < 0.0);
    let stabilising = columns
        .iter()
        .enumerate()
        .map(|(i, column)| {
            let ok: Vec<f64> = values
                .iter()
                .zip(column)
                .filter(|(_, a)| stable(a))
                .map(|(x, _)| *x)
                .collect();
            let (speed, against) = at[i];
            StabilisingRange {
                speed,
                against,
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
        against: s.against.clone(),
        against_values,
        abscissa,
        stabilising,
        unsteered_abscissa,
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

/// A gain's unit.
fn unit(gain: &str) -> &'static str {
    if gain.ends_with("_dot") {
        "N m s/rad"
    } else {
        "N m/rad"
    }
}

/// `lo to hi` of a grid (one value alone).
fn span(xs: &[f64]) -> String {
    match (xs.first(), xs.last()) {
        (Some(a), Some(b)) if a != b => format!("{} to {}", short(*a), short(*b)),
        (Some(a), _) => short(*a),
        _ => String::new(),
    }
}

impl SteerMapResult {
    /// The map's x axis: its values, what they are (`speeds`, `values of k_phi`), their unit
    /// and the axis label.
    fn x_axis(&self) -> (&[f64], String, &'static str, String) {
        match &self.against {
            Some(a) => (
                &self.against_values,
                format!("values of {a}"),
                unit(a),
                format!("{a} [{}]", unit(a)),
            ),
            None => (&self.speeds, "speeds".into(), "m/s", "speed v [m/s]".into()),
        }
    }

    /// ` at 3 m/s` for a gain × gain map, empty for a map over speeds.
    fn at_speed(&self) -> String {
        match self.against {
            Some(_) => format!(" at {} m/s", short(self.speeds[0])),
            None => String::new(),
        }
    }

    /// The varied gains: `k_phi_dot`, or `k_phi_dot × k_phi`.
    fn varied(&self) -> String {
        match &self.against {
            Some(a) => format!("{} × {a}", self.gain),
            None => self.gain.clone(),
        }
    }

    /// The fixed gains, as `k=v` (only those not 0).
    fn others(&self) -> String {
        let row = self.gains.row();
        let set: Vec<String> = SteerGains::NAMES
            .iter()
            .zip(row)
            .filter(|(n, v)| **n != self.gain && Some(**n) != self.against.as_deref() && *v != 0.0)
            .map(|(n, v)| format!("{n}={v}"))
            .collect();
        if set.is_empty() {
            "the other gains 0".into()
        } else {
            format!("the other gains {}", set.join(", "))
        }
    }

    /// One row per cell: speed, the second gain's value (in a gain × gain map), the gain's
    /// value, abscissa (empty where none), stable.
    pub fn csv(&self) -> String {
        let (xs, ..) = self.x_axis();
        let against = self
            .against
            .as_ref()
            .map_or(String::new(), |a| format!("{a},"));
        let mut out = format!("speed,{against}{},closed_loop_abscissa,stable\n", self.gain);
        for (jv, y) in self.values.iter().enumerate() {
            for (i, x) in xs.iter().enumerate() {
                let a = self.abscissa[jv * xs.len() + i];
                let (speed, against) = match self.against {
                    Some(_) => (self.speeds[0], format!("{x},")),
                    None => (*x, String::new()),
                };
                out += &format!(
                    "{speed},{against}{y},{},{}\n",
                    csv_field(a),
                    a.is_some_and(|a| a < 0.0)
                );
            }
        }
        out
    }

    /// The map: abscissa over (speed or the second gain, gain) with the stability boundary,
    /// and the weave and capsize speeds marked on a speed axis.
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
        let (xs, _, _, x_label) = self.x_axis();
        Figure::Heat(HeatMap {
            title: format!(
                "{}{} steered by {} ({})",
                self.model,
                self.at_speed(),
                self.varied(),
                self.others()
            ),
            x_label,
            y_label: format!("{} [{}]", self.gain, unit(&self.gain)),
            value_label: "max Re λ of the closed loop [1/s]".into(),
            xs: xs.to_vec(),
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
    /// (or, at one speed, the open loop) where nobody needs to steer.
    pub fn summary(&self) -> String {
        let (xs, things, x_unit, _) = self.x_axis();
        let (n, m) = (xs.len(), self.values.len());
        let of = match self.against {
            Some(_) => format!("of {} ", self.gain),
            None => String::new(),
        };
        let mut out = format!(
            "{}{} steered by {} over {n} {things} {} {x_unit} × {m} values {of}{} {} ({}; {}): \
             stable (max Re λ < 0) in {} of {} cells\n",
            self.model,
            self.at_speed(),
            self.varied(),
            span(xs),
            span(&self.values),
            unit(&self.gain),
            self.others(),
            self.params,
            self.stable_cells,
            n * m
        );
        let helped: Vec<f64> = xs
            .iter()
            .zip(&self.stabilising)
            .filter(|(_, r)| r.count > 0)
            .map(|(x, _)| *x)
            .collect();
        out += &match (helped.first(), helped.last()) {
            (Some(a), Some(b)) => format!(
                "  some value of {} stabilises it at {} of {n} {things}, from {} to {} {x_unit}\n",
                self.gain,
                helped.len(),
                short(*a),
                short(*b)
            ),
            _ => format!(
                "  no value of {} on the map stabilises it at any of its {things}\n",
                self.gain
            ),
        };
        let one_speed = self.speeds.len() == 1;
        out += &match (one_speed, self.unsteered_abscissa) {
            (true, Some(a)) => format!(
                "  nobody steering, at {} m/s it is {} (max Re λ = {a:.4} 1/s)\n",
                short(self.speeds[0]),
                if a < 0.0 { "self-stable" } else { "unstable" }
            ),
            (true, None) => "  nobody steering, its eigenvalues are not finite\n".into(),
            (false, _) if self.self_stable.is_empty() => {
                "  nobody steering, it is self-stable at no speed of the map\n".to_string()
            }
            (false, _) => {
                let bands: Vec<String> = self
                    .self_stable
                    .iter()
                    .map(|(a, b)| format!("{a:.4}–{b:.4}"))
                    .collect();
                format!(
                    "  nobody steering, it is self-stable at {} m/s (dashed lines on the map)\n",
                    bands.join(", ")
                )
            }
        };
        out
    }
}
