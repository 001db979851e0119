//! `twv uncertainty`: a measured bicycle's parameters drawn within their stated uncertainty —
//! the parameter file's `[uncertainty]` table, one standard deviation per value, independent
//! normal draws (Monte Carlo) — and, for every draw, what the study asks of a bicycle: its
//! weave and capsize speeds nobody steering ([`steady_motion`]), and one steer design's closed
//! loop at one speed (spectral abscissa, disk margins, the spec met; [`certify_steer`]).
//!
//! Sample k's draws depend only on the seed and k (ChaCha8 stream k), so the samples split into
//! shards — contiguous index ranges, one per task of a Slurm array — which [`merge`] joins into
//! the result of one run, byte for byte.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::steady::{steady_motion, SteadySettings};
use super::steer::{check_rate_filter, csv_field, finite_gains, steer_loop};
use super::steer_map::BAND_STEP;
use crate::error::{Error, Result};
use crate::linear::SteerGains;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::plot::{Curve, Figure, LineChart};
use crate::progress::{Progress, Silent};
use crate::sweep::Shard;
use crate::tune::steer::{certify_steer, tune_steer, SteerTuneOptions};
use crate::tune::{Spec, TuneStatus};

/// The most draws one run takes (each is a band search of ~300 linearisations).
pub const MAX_DRAWS: usize = 100_000;

/// How close the weave and capsize speeds of a draw are found [m/s]: far below the spread the
/// parameters' uncertainty gives them (centimetres per second).
const BOUND_TOLERANCE: f64 = 1e-9;

/// Settings of `twv uncertainty`. Defaults beside each field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UncertaintySettings {
    /// Number of draws. Default 200.
    pub samples: usize,
    /// Seed of the draws. Default 1.
    pub seed: u64,
    /// The speeds searched for the self-stable band nobody steering: lowest and highest
    /// [m/s]. Default 0 and 10.
    pub lo: f64,
    pub hi: f64,
    /// The speed at which the steer design is checked on every draw [m/s]. Default 3 (below
    /// every measured bicycle's weave speed: someone must steer).
    pub speed: f64,
    /// The steer gains checked on every draw; `None` (default): tuned on the nominal bicycle
    /// at `speed` to `spec` (Clarabel, as `twv steer`).
    pub gains: Option<SteerGains>,
    /// τ of the steer law's filter on the rates [s], in the tuning and every draw's check;
    /// `None` (default): unfiltered.
    pub rate_filter: Option<f64>,
    /// The margins each draw's closed loop is checked against. Default `dpm>=45`.
    pub spec: Spec,
    /// Which draws this run computes: shard i of N, a contiguous range of the indices.
    /// Default 0/1 (all).
    pub shard: Shard,
}

impl Default for UncertaintySettings {
    fn default() -> Self {
        Self {
            samples: 200,
            seed: 1,
            lo: 0.0,
            hi: 10.0,
            speed: 3.0,
            gains: None,
            rate_filter: None,
            spec: "dpm>=45".parse().expect("a valid default spec"),
            shard: Shard::WHOLE,
        }
    }
}

impl UncertaintySettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if self.samples == 0 || self.samples > MAX_DRAWS {
            return Err(Error::input(
                "samples",
                format!("{}: from 1 to {MAX_DRAWS} draws", self.samples),
            ));
        }
        if !(self.lo.is_finite() && self.hi.is_finite() && self.lo >= 0.0 && self.hi > self.lo) {
            return Err(Error::input(
                "speeds",
                format!(
                    "{}:{} needs finite 0 ≤ LO < HI (straight running forward)",
                    self.lo, self.hi
                ),
            ));
        }
        if (self.hi - self.lo) / BAND_STEP > super::steady::MAX_SPEEDS as f64 {
            return Err(Error::input(
                "speeds",
                format!("{}:{} is too wide a range to search", self.lo, self.hi),
            ));
        }
        if !(self.speed.is_finite() && self.speed > 0.0 && self.speed <= 1e3) {
            return Err(Error::input(
                "speed",
                format!("{} m/s: a speed in (0, 1000]", self.speed),
            ));
        }
        if let Some(g) = &self.gains {
            finite_gains(g)?;
        }
        check_rate_filter(self.rate_filter)?;
        crate::tune::steer::check_spec(&self.spec)?;
        Shard::new(self.shard.index, self.shard.count)
            .map_err(|e| Error::input("shard", e.to_string()))?;
        if self.shard.count > self.samples {
            return Err(Error::input(
                "shard",
                format!(
                    "{} shards of {} draws: at most one shard per draw",
                    self.shard.count, self.samples
                ),
            ));
        }
        Ok(())
    }
}

/// How one bicycle's evaluation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SampleStatus {
    /// Every quantity computed.
    Ok,
    /// The drawn values break a rule of the parameter file (a negative mass, an inertia
    /// tensor that is not one): not a bicycle, left out of every distribution.
    Unphysical,
    /// The linearisation or an eigenvalue computation failed (non-finite numbers).
    Failed,
}

/// What one bicycle (the nominal one or a draw) gives.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    pub status: SampleStatus,
    /// Lower bound of the first self-stable range, where an oscillating pair becomes stable
    /// [m/s] (`None`: none in the searched speeds).
    pub weave_speed: Option<f64>,
    /// Its upper bound, where a real mode becomes unstable [m/s].
    pub capsize_speed: Option<f64>,
    /// Self-stable somewhere in the searched speeds.
    pub self_stable: bool,
    /// Largest real part of the steered closed loop's eigenvalues at the check speed [1/s].
    pub closed_loop_abscissa: Option<f64>,
    /// Disk phase margin [deg] and disk gain margin (upper factor) at the steer torque.
    pub disk_phase_margin_deg: Option<f64>,
    pub disk_gain_margin: Option<f64>,
    /// The closed loop is stable at the check speed.
    pub stable: bool,
    /// Stable and every requirement of the spec met.
    pub meets_spec: bool,
}

impl Evaluation {
    fn without_value(status: SampleStatus) -> Self {
        Self {
            status,
            weave_speed: None,
            capsize_speed: None,
            self_stable: false,
            closed_loop_abscissa: None,
            disk_phase_margin_deg: None,
            disk_gain_margin: None,
            stable: false,
            meets_spec: false,
        }
    }
}

/// One draw: its index, the values drawn (IR order) and what they give.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    pub index: usize,
    pub params: Vec<f64>,
    #[serde(flatten)]
    pub evaluation: Evaluation,
}

/// Summary statistics of one quantity over the draws that have it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Draws with a value.
    pub count: usize,
    pub mean: f64,
    /// Sample standard deviation (n − 1; 0 for one value).
    pub sd: f64,
    pub min: f64,
    /// 5 %, 50 % and 95 % quantiles (linear interpolation between order statistics).
    pub p05: f64,
    pub p50: f64,
    pub p95: f64,
    pub max: f64,
}

impl Spread {
    /// The statistics of `values` (`None` when there are none).
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        let quantile = |p: f64| {
            let h = p * (n - 1) as f64;
            let (i, f) = (h.floor() as usize, h - h.floor());
            if i + 1 < n {
                v[i] + f * (v[i + 1] - v[i])
            } else {
                v[n - 1]
            }
        };
        Some(Self {
            count: n,
            mean,
            sd,
            min: v[0],
            p05: quantile(0.05),
            p50: quantile(0.5),
            p95: quantile(0.95),
            max: v[n - 1],
        })
    }
}

/// A parameter that varies, with its nominal value and standard deviation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Varied {
    pub name: String,
    pub value: f64,
    pub sd: f64,
}

/// How the draws came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UncertaintyVerdict {
    /// The steer design's closed loop is stable for every physical draw.
    AllStable,
    /// It is unstable (or could not be computed) for some draw, or no draw was physical.
    NotAllStable,
}

/// The result of `twv uncertainty` (of one shard, or of all of them merged).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UncertaintyResult {
    pub model: String,
    /// Where the nominal values and their uncertainty came from.
    pub params: String,
    /// Every parameter's IR name (the order of each sample's `params`).
    pub names: Vec<String>,
    /// The parameters with a standard deviation > 0.
    pub varied: Vec<Varied>,
    /// Draws of the whole run, their seed, and the shard these samples are (0/1 when whole).
    pub samples_total: usize,
    pub seed: u64,
    pub shard: Shard,
    /// The speeds searched for the band [m/s].
    pub lo: f64,
    pub hi: f64,
    /// The check speed [m/s], the gains checked there, whether they were tuned on the nominal
    /// bicycle (and how that tuning ended), and the spec.
    pub speed: f64,
    pub gains: SteerGains,
    pub design: Option<TuneStatus>,
    pub spec: Spec,
    /// The bicycle at its nominal values.
    pub nominal: Evaluation,
    /// The draws, by index.
    pub samples: Vec<Sample>,
    /// Over the physical draws that have each: weave and capsize speed [m/s], closed-loop
    /// spectral abscissa [1/s], disk phase margin [deg].
    pub weave_speed: Option<Spread>,
    pub capsize_speed: Option<Spread>,
    pub closed_loop_abscissa: Option<Spread>,
    pub disk_phase_margin_deg: Option<Spread>,
    /// Counts over the draws: physical, unphysical, self-stable somewhere, steered stable, spec
    /// met.
    pub physical: usize,
    pub unphysical: usize,
    pub self_stable: usize,
    pub stable: usize,
    pub meets_spec: usize,
    pub verdict: UncertaintyVerdict,
}

/// The values of draw `index`: nominal + sd · z, z standard normal from ChaCha8 stream `index`
/// of `seed` (one z per parameter, drawn even where sd = 0, so a parameter's draws do not
/// depend on which others vary).
pub fn draw(nominal: &[f64], sd: &[f64], seed: u64, index: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index as u64);
    nominal
        .iter()
        .zip(sd)
        .map(|(v, s)| {
            let z: f64 = StandardNormal.sample(&mut rng);
            v + s * z
        })
        .collect()
}

/// The band nobody steering and the design's closed loop of `model`.
fn evaluate(model: &ResolvedModel, s: &UncertaintySettings, gains: &SteerGains) -> Evaluation {
    let band = steady_motion(
        model,
        &SteadySettings {
            lo: s.lo,
            hi: s.hi,
            step: BAND_STEP,
            bound_tolerance: BOUND_TOLERANCE,
        },
        &Silent,
    );
    let certificate = steer_loop(model, s.speed)
        .and_then(|lp| Ok(lp.with_rate_filter(s.rate_filter)?))
        .ok()
        .and_then(|lp| certify_steer(&lp, gains, &s.spec).ok());
    match (band, certificate) {
        (Ok(band), Some(c)) => {
            let a = &c.analysis;
            let finite = |x: f64| x.is_finite().then_some(x);
            Evaluation {
                status: SampleStatus::Ok,
                weave_speed: band.weave_speed,
                capsize_speed: band.capsize_speed,
                self_stable: !band.stable_ranges.is_empty(),
                closed_loop_abscissa: finite(a.closed_loop.spectral_abscissa),
                disk_phase_margin_deg: finite(a.margins.disk.phase_deg),
                disk_gain_margin: finite(a.margins.disk.gain_high),
                stable: a.closed_loop.stable,
                meets_spec: c.meets_spec,
            }
        }
        _ => Evaluation::without_value(SampleStatus::Failed),
    }
}

/// The steer gains every draw is checked with: the given ones, or those tuned on the nominal
/// bicycle at the check speed.
fn design(
    model: &ResolvedModel,
    s: &UncertaintySettings,
    progress: &dyn Progress,
) -> Result<(SteerGains, Option<TuneStatus>)> {
    if let Some(g) = s.gains {
        return Ok((g, None));
    }
    let lp = steer_loop(model, s.speed)?.with_rate_filter(s.rate_filter)?;
    let stop = || progress.cancelled();
    let t = tune_steer(&lp, &s.spec, &SteerTuneOptions::default(), &stop)?;
    match t.certificate {
        Some(c) => Ok((c.gains, Some(t.status))),
        None => Err(Error::input(
            "gains",
            format!(
                "no stabilising steer gains found for the nominal {} at {} m/s: give --gains",
                model.name(),
                s.speed
            ),
        )),
    }
}

/// Runs `twv uncertainty` on this shard's draws.
pub fn uncertainty(
    model: &ResolvedModel,
    s: &UncertaintySettings,
    progress: &dyn Progress,
) -> Result<UncertaintyResult> {
    s.validate()?;
    let names: Vec<String> = model.ir.params().iter().map(|p| p.name.clone()).collect();
    let varied: Vec<Varied> = names
        .iter()
        .zip(model.params.iter().zip(&model.uncertainty))
        .filter(|(_, (_, sd))| **sd > 0.0)
        .map(|(name, (value, sd))| Varied {
            name: name.clone(),
            value: *value,
            sd: *sd,
        })
        .collect();
    if varied.is_empty() {
        return Err(Error::input(
            "params",
            format!(
                "{} gives no uncertainty: a parameter file with an [uncertainty] table of \
                 standard deviations is needed (e.g. vehicles/bicycles/browser.toml)",
                model.params_origin
            ),
        ));
    }
    let (gains, design_status) = design(model, s, progress)?;
    let nominal = evaluate(model, s, &gains);
    let range = s.shard.range(s.samples);
    progress.start(range.len() as u64, "draws");
    let samples = range
        .into_par_iter()
        .map(|index| {
            if progress.cancelled() {
                return Err(Error::Interrupted);
            }
            let params = draw(&model.params, &model.uncertainty, s.seed, index);
            let values: Vec<(String, f64)> = names.iter().cloned().zip(params.clone()).collect();
            let evaluation = match model.with_param_values(&values, &format!("draw {index}")) {
                Ok(m) => evaluate(&m, s, &gains),
                Err(_) => Evaluation::without_value(SampleStatus::Unphysical),
            };
            progress.advance(1);
            Ok(Sample {
                index,
                params,
                evaluation,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(UncertaintyResult {
        model: model.name().to_string(),
        params: model.params_origin.clone(),
        names,
        varied,
        samples_total: s.samples,
        seed: s.seed,
        shard: s.shard,
        lo: s.lo,
        hi: s.hi,
        speed: s.speed,
        gains,
        design: design_status,
        spec: s.spec.clone(),
        nominal,
        samples,
        weave_speed: None,
        capsize_speed: None,
        closed_loop_abscissa: None,
        disk_phase_margin_deg: None,
        physical: 0,
        unphysical: 0,
        self_stable: 0,
        stable: 0,
        meets_spec: 0,
        verdict: UncertaintyVerdict::NotAllStable,
    }
    .tallied())
}

/// Joins the shards of one run (any order) into the result of the whole run: the same
/// settings and nominal bicycle, every shard 0..N once, the samples by index.
pub fn merge(mut parts: Vec<UncertaintyResult>) -> Result<UncertaintyResult> {
    let bad = |reason: String| Error::input("shards", reason);
    let Some(first) = parts.first() else {
        return Err(bad("no shard results to merge".into()));
    };
    let count = first.shard.count;
    let samples_total = first.samples_total;
    // Everything but the shard and its samples (the tallies of no samples are the same).
    let same = |p: &UncertaintyResult| {
        UncertaintyResult {
            shard: Shard::WHOLE,
            samples: Vec::new(),
            ..p.clone()
        }
        .tallied()
    };
    let key = same(first);
    if let Some(other) = parts.iter().find(|p| same(p) != key) {
        return Err(bad(format!(
            "shard {}/{} is of another run (model, parameters, seed, draws, speeds or design \
             differ)",
            other.shard.index, other.shard.count
        )));
    }
    parts.sort_by_key(|p| p.shard.index);
    let indices: Vec<(usize, usize)> = parts
        .iter()
        .map(|p| (p.shard.index, p.shard.count))
        .collect();
    if indices != (0..count).map(|i| (i, count)).collect::<Vec<_>>() {
        return Err(bad(format!(
            "need each of the {count} shards once; have {}",
            indices
                .iter()
                .map(|(i, n)| format!("{i}/{n}"))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let samples: Vec<Sample> = parts.iter().flat_map(|p| p.samples.clone()).collect();
    if samples.len() != samples_total || samples.iter().enumerate().any(|(i, s)| s.index != i) {
        return Err(bad(format!(
            "the shards hold {} draws, not the run's {samples_total} in order",
            samples.len()
        )));
    }
    Ok(UncertaintyResult {
        shard: Shard::WHOLE,
        samples,
        ..key
    }
    .tallied())
}

impl UncertaintyResult {
    /// The statistics, counts and verdict recomputed from the samples.
    fn tallied(mut self) -> Self {
        let ok: Vec<&Evaluation> = self
            .samples
            .iter()
            .map(|s| &s.evaluation)
            .filter(|e| e.status != SampleStatus::Unphysical)
            .collect();
        let values = |f: fn(&Evaluation) -> Option<f64>| -> Vec<f64> {
            ok.iter().filter_map(|e| f(e)).collect()
        };
        self.weave_speed = Spread::of(&values(|e| e.weave_speed));
        self.capsize_speed = Spread::of(&values(|e| e.capsize_speed));
        self.closed_loop_abscissa = Spread::of(&values(|e| e.closed_loop_abscissa));
        self.disk_phase_margin_deg = Spread::of(&values(|e| e.disk_phase_margin_deg));
        self.physical = ok.len();
        self.unphysical = self.samples.len() - ok.len();
        self.self_stable = ok.iter().filter(|e| e.self_stable).count();
        self.stable = ok.iter().filter(|e| e.stable).count();
        self.meets_spec = ok.iter().filter(|e| e.meets_spec).count();
        self.verdict = if self.physical > 0 && self.stable == self.physical {
            UncertaintyVerdict::AllStable
        } else {
            UncertaintyVerdict::NotAllStable
        };
        self
    }

    /// The gains as `k=v` (only those not 0).
    fn gains_text(&self) -> String {
        let set: Vec<String> = SteerGains::NAMES
            .iter()
            .zip(self.gains.row())
            .filter(|(_, v)| *v != 0.0)
            .map(|(n, v)| format!("{n}={v:.4}"))
            .collect();
        if set.is_empty() {
            "no gains (nobody steering)".into()
        } else {
            set.join(", ")
        }
    }

    /// One row per draw: index, status, the quantities, then the drawn values.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "index,status,weave_speed,capsize_speed,self_stable,closed_loop_abscissa,\
             disk_phase_margin_deg,disk_gain_margin,stable,meets_spec",
        );
        for n in &self.names {
            out += &format!(",{n}");
        }
        out.push('\n');
        for s in &self.samples {
            let e = &s.evaluation;
            let mut row = vec![
                s.index.to_string(),
                format!("{:?}", e.status).to_lowercase(),
                csv_field(e.weave_speed),
                csv_field(e.capsize_speed),
                e.self_stable.to_string(),
                csv_field(e.closed_loop_abscissa),
                csv_field(e.disk_phase_margin_deg),
                csv_field(e.disk_gain_margin),
                e.stable.to_string(),
                e.meets_spec.to_string(),
            ];
            row.extend(s.params.iter().map(|v| format!("{v}")));
            out += &(row.join(",") + "\n");
        }
        out
    }

    /// The empirical distribution function of one quantity over the physical draws: the
    /// fraction of draws with a value ≤ x, as a staircase.
    fn ecdf(&self, name: &str, f: fn(&Evaluation) -> Option<f64>) -> Curve {
        let mut v: Vec<f64> = self
            .samples
            .iter()
            .map(|s| &s.evaluation)
            .filter(|e| e.status != SampleStatus::Unphysical)
            .filter_map(f)
            .collect();
        v.sort_by(f64::total_cmp);
        let n = self.physical.max(1) as f64;
        let points = v
            .iter()
            .enumerate()
            .flat_map(|(i, x)| [(*x, i as f64 / n), (*x, (i + 1) as f64 / n)])
            .collect();
        Curve {
            name: name.into(),
            points,
        }
    }

    /// A vertical line at the nominal value (drawn over the distribution's full height).
    fn nominal_line(name: &str, x: Option<f64>) -> Option<Curve> {
        x.map(|x| Curve {
            name: name.into(),
            points: vec![(x, 0.0), (x, 1.0)],
        })
    }

    /// The weave and capsize speeds' distributions, and the disk phase margin's, each with the
    /// nominal bicycle's value.
    pub fn figures(&self) -> Vec<(String, Figure)> {
        // The parameter file's name, without its folder or "(embedded)".
        let file = self
            .params
            .rsplit('/')
            .next()
            .unwrap_or(&self.params)
            .trim_end_matches(" (embedded)");
        let title = format!("{} with {file} ({} draws)", self.model, self.samples.len());
        let mut speeds = vec![
            self.ecdf("weave speed", |e| e.weave_speed),
            self.ecdf("capsize speed", |e| e.capsize_speed),
        ];
        speeds.extend(Self::nominal_line(
            "nominal weave",
            self.nominal.weave_speed,
        ));
        speeds.extend(Self::nominal_line(
            "nominal capsize",
            self.nominal.capsize_speed,
        ));
        let mut margin = vec![self.ecdf("disk phase margin", |e| e.disk_phase_margin_deg)];
        margin.extend(Self::nominal_line(
            "nominal",
            self.nominal.disk_phase_margin_deg,
        ));
        vec![
            (
                "speeds.svg".into(),
                Figure::Line(LineChart::new(
                    &format!("weave and capsize speeds of {title}"),
                    "speed v [m/s]",
                    "fraction of draws ≤ v",
                    (900, 520),
                    speeds,
                )),
            ),
            (
                "margins.svg".into(),
                Figure::Line(LineChart::new(
                    // The gains are in the summary and the JSON: a title that names them all
                    // does not fit the figure.
                    &format!("disk phase margin at {} m/s of {title}", self.speed),
                    "disk phase margin [deg]",
                    "fraction of draws ≤ margin",
                    (900, 520),
                    margin,
                )),
            ),
        ]
    }

    /// The file names of this result: `uncertainty.*`, or `uncertainty-shard-i-of-N.*` for a
    /// shard (so the tasks of an array can share one folder).
    pub fn stem(&self) -> String {
        if self.shard.count > 1 {
            format!(
                "uncertainty-shard-{}-of-{}",
                self.shard.index, self.shard.count
            )
        } else {
            "uncertainty".into()
        }
    }

    /// uncertainty.csv, uncertainty.json, speeds.svg and margins.svg (and PNGs); a shard
    /// writes its CSV and JSON only, the merged run draws the figures.
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        let stem = self.stem();
        f.text(&format!("{stem}.csv"), self.csv());
        f.json(&format!("{stem}.json"), self);
        if self.shard.count > 1 {
            return Ok(f.shared());
        }
        for (name, fig) in self.figures() {
            f.figure(&name, &fig)?;
        }
        Ok(f)
    }

    /// The draws, each quantity's spread against the nominal bicycle's value, and the counts.
    pub fn summary(&self) -> String {
        let n = self.samples.len();
        let mut out = format!(
            "{} ({}): {n} draws{} of {} parameters within their standard deviations (seed {})\n",
            self.model,
            self.params,
            if self.shard.count > 1 {
                format!(
                    " (shard {}/{} of {})",
                    self.shard.index, self.shard.count, self.samples_total
                )
            } else {
                String::new()
            },
            self.varied.len(),
            self.seed
        );
        let line = |what: &str, unit: &str, nominal: Option<f64>, s: &Option<Spread>| {
            let nominal = nominal.map_or("none".into(), |v| format!("{v:.4} {unit}"));
            match s {
                Some(s) => format!(
                    "  {what}: nominal {nominal}; 5–95 % {:.4}–{:.4} {unit} (mean {:.4}, sd \
                     {:.4}) in {} of {} physical draws\n",
                    s.p05, s.p95, s.mean, s.sd, s.count, self.physical
                ),
                None => format!("  {what}: nominal {nominal}; in none of the draws\n"),
            }
        };
        out += &line(
            "weave speed",
            "m/s",
            self.nominal.weave_speed,
            &self.weave_speed,
        );
        out += &line(
            "capsize speed",
            "m/s",
            self.nominal.capsize_speed,
            &self.capsize_speed,
        );
        out += &format!(
            "  self-stable somewhere in {}–{} m/s: {} of {} physical draws\n",
            self.lo, self.hi, self.self_stable, self.physical
        );
        out += &format!(
            "  steered at {} m/s by {} ({}):\n",
            self.speed,
            self.gains_text(),
            match self.design {
                Some(t) => format!("tuned on the nominal bicycle to `{}`, {t:?}", self.spec),
                None => "given".into(),
            }
        );
        out += &line(
            "  disk phase margin",
            "deg",
            self.nominal.disk_phase_margin_deg,
            &self.disk_phase_margin_deg,
        );
        out += &format!(
            "    closed loop stable in {} of {} physical draws; `{}` met in {}\n",
            self.stable, self.physical, self.spec, self.meets_spec
        );
        if self.unphysical > 0 {
            out += &format!(
                "  {} draws broke a parameter rule (not a bicycle) and are left out\n",
                self.unphysical
            );
        }
        out
    }
}

/// The shard files `uncertainty-shard-i-of-N.json` in `dir`, sorted by name.
pub fn shard_files(dir: &std::path::Path) -> Result<Vec<std::path::PathBuf>> {
    crate::sweep::shard_files_named(dir, "uncertainty-shard-")
        .map_err(|e| Error::input("dir", format!("{}: cannot be read: {e}", dir.display())))
}

/// Reads the shards of one run in `dir`, merges them ([`merge`]) and writes the whole run's
/// files there (all or nothing).
pub fn merge_dir(dir: &std::path::Path) -> Result<(UncertaintyResult, Vec<std::path::PathBuf>)> {
    let paths = shard_files(dir)?;
    if paths.is_empty() {
        return Err(Error::input(
            "dir",
            format!("{}: no uncertainty-shard-*-of-*.json files", dir.display()),
        ));
    }
    let parts = paths
        .iter()
        .map(|path| {
            let bad =
                |reason: String| Error::input("shard", format!("{}: {reason}", path.display()));
            let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
            serde_json::from_str::<UncertaintyResult>(&text).map_err(|e| bad(e.to_string()))
        })
        .collect::<Result<Vec<_>>>()?;
    let whole = merge(parts)?;
    let written = whole.files()?.write(dir)?.files;
    Ok((whole, written))
}
