//! Linearisation about a steady motion against speed: `twv linear --speed LO:HI:STEP`. For a
//! model whose IR describes its straight running (`mechanics.steady_motion` and the function
//! `steady`, the state at unit speed; the Whipple bicycle), the eigenvalues of the Jacobian
//! restricted to the studied modes (lean and steer) at every speed of a grid, and the
//! self-stable speed ranges: where the largest real part is negative, each bound refined by
//! bisection on the sign of that real part.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use twv_ir::{Function, Ir};

use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::plot::{Curve, Figure, LineChart};
use crate::progress::Progress;

/// The most speeds one sweep evaluates.
pub const MAX_SPEEDS: usize = 100_000;

/// Speeds between progress reports (and looks at the cancel flag): about 0.1 s of the bicycle
/// on the interpreter.
const PROGRESS_CHUNK: usize = 500;

/// Settings of a speed sweep, defaults beside each field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SteadySettings {
    /// Lowest speed [m/s]. Default 0.
    pub lo: f64,
    /// Highest speed [m/s]. Default 10.
    pub hi: f64,
    /// Grid step [m/s]. Default 0.01.
    pub step: f64,
    /// Bounds of the stable ranges are refined until they are this close [m/s]. Default 1e-13.
    pub bound_tolerance: f64,
}

impl Default for SteadySettings {
    fn default() -> Self {
        Self {
            lo: 0.0,
            hi: 10.0,
            step: 0.01,
            bound_tolerance: 1e-13,
        }
    }
}

impl SteadySettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.lo.is_finite() && self.hi.is_finite() && self.hi > self.lo) {
            return Err(Error::input(
                "speed",
                format!("{}:{} needs finite LO < HI", self.lo, self.hi),
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(Error::input(
                "speed",
                format!("step {} must be finite and > 0", self.step),
            ));
        }
        let n = ((self.hi - self.lo) / self.step).floor() + 1.0;
        if n > MAX_SPEEDS as f64 {
            return Err(Error::input(
                "speed",
                format!("{n} speeds is more than {MAX_SPEEDS}"),
            ));
        }
        if !(self.bound_tolerance.is_finite() && self.bound_tolerance > 0.0) {
            return Err(Error::input(
                "bound_tolerance",
                format!("{} must be finite and > 0", self.bound_tolerance),
            ));
        }
        Ok(())
    }

    /// The grid: lo, lo + step, … ≤ hi (computed as lo + k·step, no accumulated rounding).
    pub fn speeds(&self) -> Vec<f64> {
        let n = ((self.hi - self.lo) / self.step + 1e-9).floor() as usize + 1;
        (0..n).map(|k| self.lo + k as f64 * self.step).collect()
    }
}

/// One speed's eigenvalues (re, im), sorted by real part, then imaginary part.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpeedPoint {
    pub speed: f64,
    pub eigenvalues: Vec<(f64, f64)>,
    /// The largest real part: < 0 means self-stable at this speed.
    pub spectral_abscissa: f64,
}

/// How the sweep judged the motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SteadyVerdict {
    /// Self-stable somewhere in the grid (see `stable_ranges`).
    SelfStable,
    /// Unstable at every speed of the grid.
    NowhereStable,
}

/// The result of a speed sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteadyResult {
    pub model: String,
    /// The states the Jacobian is restricted to.
    pub modes: Vec<String>,
    /// The state that carries the speed.
    pub speed_state: String,
    pub points: Vec<SpeedPoint>,
    /// Speed intervals where every studied eigenvalue has a negative real part; a bound at
    /// the grid's edge is the edge (the range may go on).
    pub stable_ranges: Vec<(f64, f64)>,
    /// Each stable range with the kind of mode that crosses zero at each bound.
    pub ranges: Vec<StableRange>,
    /// The lowest speed where an oscillating pair becomes stable (a bicycle's weave speed):
    /// the lower bound of the first stable range when a complex pair crosses there [m/s].
    pub weave_speed: Option<f64>,
    /// The speed where a real mode becomes unstable above a stable range (a bicycle's capsize
    /// speed): the upper bound of the first stable range when a real eigenvalue crosses there
    /// [m/s].
    pub capsize_speed: Option<f64>,
    pub verdict: SteadyVerdict,
}

/// What crosses the imaginary axis at a bound of a stable range.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Crossing {
    /// A complex pair (an oscillation: a bicycle's weave).
    Oscillatory,
    /// A real eigenvalue (a divergence: a bicycle's capsize).
    Real,
    /// The bound is the grid's edge: nothing crosses there on the grid.
    GridEdge,
}

/// A stable speed range with what bounds it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StableRange {
    /// Lowest stable speed [m/s].
    pub lo: f64,
    /// Highest stable speed [m/s].
    pub hi: f64,
    /// What crosses at `lo`.
    pub lo_crossing: Crossing,
    /// What crosses at `hi`.
    pub hi_crossing: Crossing,
}

/// An eigenvalue's imaginary part counts as zero below this, relative to its modulus.
const REAL_TOLERANCE: f64 = 1e-9;

/// What crosses at `speed`: the eigenvalue with the largest real part there.
fn crossing_kind(motion: &Motion, speed: f64, work: &mut Vec<f64>) -> Result<Crossing> {
    let ev = motion.eigenvalues(speed, work)?;
    let top = ev
        .iter()
        .copied()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap_or((0.0, 0.0));
    Ok(
        if top.1.abs() > REAL_TOLERANCE * top.0.hypot(top.1).max(1.0) {
            Crossing::Oscillatory
        } else {
            Crossing::Real
        },
    )
}

/// The model's description of its steady motion, read from the IR.
struct Motion<'a> {
    jac: &'a Function,
    unit: Vec<f64>,
    modes: Vec<usize>,
    params: &'a [f64],
    nu: usize,
    speed_state: String,
    mode_names: Vec<String>,
}

/// Checks one steady motion's speed (`--speed` of lyapunov, linearize, phase): straight running
/// forward needs a finite speed ≥ 0.
pub fn check_speed(v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::input(
            "speed",
            format!("{v}: straight running forward needs a finite speed ≥ 0"),
        ))
    }
}

/// The state of the model's steady motion at `speed` (the bicycle: upright, straight, the rear
/// wheel turning at speed / r_R), for a model whose IR describes one.
pub fn steady_state(model: &ResolvedModel, speed: f64) -> Result<Vec<f64>> {
    Ok(Motion::of(model)?.state(speed))
}

/// The model linearised about its steady motion at `speed`, restricted to the studied modes:
/// ẋ = A x + B u on the modes (the bicycle's lean, steer and their rates), with every input.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalPlant {
    /// The speed [m/s].
    pub speed: f64,
    /// The studied states, in the IR's order.
    pub modes: Vec<String>,
    /// ∂f/∂x restricted to the modes (rows and columns).
    pub a: DMatrix<f64>,
    /// ∂f/∂u on the modes' rows, one column per input.
    pub b: DMatrix<f64>,
}

/// [`ModalPlant`] of `model` at `speed`, for a model whose IR describes a steady motion.
pub fn modal_plant(model: &ResolvedModel, speed: f64) -> Result<ModalPlant> {
    let motion = Motion::of(model)?;
    let mut work = Vec::new();
    let a = motion.modal_jacobian(speed, &mut work)?;
    let jac_u = model
        .ir
        .function("jac_u")
        .ok_or_else(|| unsupported(&model.ir, "its IR has no function `jac_u`"))?;
    let (x, u) = (motion.state(speed), vec![0.0; motion.nu]);
    work.resize(jac_u.n_values(), 0.0);
    jac_u
        .eval(&x, &u, motion.params, &mut work)
        .map_err(|e| Error::input("steady", e.to_string()))?;
    let mut b = DMatrix::zeros(motion.modes.len(), motion.nu);
    for (row, col, value) in jac_u.outputs()[0].entries() {
        if let Some(i) = motion.modes.iter().position(|&m| m == row) {
            b[(i, col)] = work[value];
        }
    }
    if b.iter().any(|e| !e.is_finite()) {
        return Err(Error::NonFinite {
            what: "the input Jacobian".into(),
            at: format!("speed {speed}"),
        });
    }
    Ok(ModalPlant {
        speed,
        modes: motion.mode_names.clone(),
        a,
        b,
    })
}

fn unsupported(ir: &Ir, reason: &str) -> Error {
    Error::Unsupported {
        model: ir.model().to_string(),
        reason: reason.to_string(),
    }
}

impl<'a> Motion<'a> {
    fn of(model: &'a ResolvedModel) -> Result<Self> {
        let ir = &model.ir;
        let steady = model.steady_motion().ok_or_else(|| {
            unsupported(
                ir,
                "its IR describes no steady motion (mechanics.steady_motion)",
            )
        })?;
        let function = ir
            .function("steady")
            .ok_or_else(|| unsupported(ir, "its IR has no function `steady`"))?;
        let jac = ir
            .function("jac_x")
            .ok_or_else(|| unsupported(ir, "its IR has no function `jac_x`"))?;
        let mut work = vec![0.0; function.n_values()];
        let (x0, u0) = (vec![0.0; ir.nx()], vec![0.0; ir.nu()]);
        function
            .eval(&x0, &u0, &model.params, &mut work)
            .map_err(|e| Error::input("steady", e.to_string()))?;
        let mut unit = vec![0.0; ir.nx()];
        for (row, _, value) in function.outputs()[0].entries() {
            unit[row] = work[value];
        }
        let modes = steady
            .modes
            .iter()
            .map(|name| {
                model.state_index(name).ok_or_else(|| {
                    unsupported(ir, &format!("steady motion mode `{name}` is not a state"))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            jac,
            unit,
            modes,
            params: &model.params,
            nu: ir.nu(),
            speed_state: steady.speed_state.clone(),
            mode_names: steady.modes.clone(),
        })
    }

    /// The state of the steady motion at speed v.
    fn state(&self, v: f64) -> Vec<f64> {
        self.unit.iter().map(|s| v * s).collect()
    }

    /// The studied eigenvalues at speed v, sorted.
    fn eigenvalues(&self, v: f64, work: &mut Vec<f64>) -> Result<Vec<(f64, f64)>> {
        let a = self.modal_jacobian(v, work)?;
        let mut ev: Vec<(f64, f64)> = a
            .complex_eigenvalues()
            .iter()
            .map(|c| (c.re, c.im))
            .collect();
        ev.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)));
        Ok(ev)
    }

    /// ∂f/∂x at the steady motion of speed v, restricted to the studied modes.
    fn modal_jacobian(&self, v: f64, work: &mut Vec<f64>) -> Result<DMatrix<f64>> {
        let x = self.state(v);
        let u = vec![0.0; self.nu];
        work.resize(self.jac.n_values(), 0.0);
        self.jac
            .eval(&x, &u, self.params, work)
            .map_err(|e| Error::input("steady", e.to_string()))?;
        let k = self.modes.len();
        let mut a = DMatrix::zeros(k, k);
        let out = &self.jac.outputs()[0];
        for (row, col, value) in out.entries() {
            if let (Some(i), Some(j)) = (
                self.modes.iter().position(|&m| m == row),
                self.modes.iter().position(|&m| m == col),
            ) {
                a[(i, j)] = work[value];
            }
        }
        if a.iter().any(|e| !e.is_finite()) {
            return Err(Error::NonFinite {
                what: "the Jacobian".into(),
                at: format!("speed {v}"),
            });
        }
        Ok(a)
    }

    fn abscissa(&self, v: f64, work: &mut Vec<f64>) -> Result<f64> {
        Ok(spectral_abscissa(&self.eigenvalues(v, work)?))
    }
}

/// The largest real part (< 0: every studied mode decays).
fn spectral_abscissa(eigenvalues: &[(f64, f64)]) -> f64 {
    eigenvalues
        .iter()
        .fold(f64::NEG_INFINITY, |m, e| m.max(e.0))
}

/// The speed in [a, b] where the spectral abscissa changes sign (it does at the ends), by
/// bisection to `tol`.
fn crossing(
    motion: &Motion<'_>,
    mut a: f64,
    mut b: f64,
    tol: f64,
    work: &mut Vec<f64>,
) -> Result<f64> {
    let stable_a = motion.abscissa(a, work)? < 0.0;
    while b - a > tol {
        let mid = 0.5 * (a + b);
        if mid <= a || mid >= b {
            break;
        }
        if (motion.abscissa(mid, work)? < 0.0) == stable_a {
            a = mid;
        } else {
            b = mid;
        }
    }
    Ok(0.5 * (a + b))
}

/// The eigenvalues of the studied modes against speed, and the self-stable ranges.
///
/// `progress` hears of every [`PROGRESS_CHUNK`] speeds, and a cancellation stops the run there.
pub fn steady_motion(
    model: &ResolvedModel,
    settings: &SteadySettings,
    progress: &dyn Progress,
) -> Result<SteadyResult> {
    settings.validate()?;
    let motion = Motion::of(model)?;
    let mut work = Vec::new();
    let speeds = settings.speeds();
    progress.start(speeds.len() as u64, "speeds");
    let points = speeds
        .into_iter()
        .enumerate()
        .map(|(k, v)| {
            if k % PROGRESS_CHUNK == PROGRESS_CHUNK - 1 {
                progress.advance(PROGRESS_CHUNK as u64);
                if progress.cancelled() {
                    return Err(Error::Interrupted);
                }
            }
            let eigenvalues = motion.eigenvalues(v, &mut work)?;
            Ok(SpeedPoint {
                speed: v,
                spectral_abscissa: spectral_abscissa(&eigenvalues),
                eigenvalues,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let mut stable_ranges = Vec::new();
    let mut start: Option<f64> = None;
    for (k, p) in points.iter().enumerate() {
        let stable = p.spectral_abscissa < 0.0;
        match (stable, start) {
            (true, None) => {
                start = Some(if k == 0 {
                    p.speed
                } else {
                    crossing(
                        &motion,
                        points[k - 1].speed,
                        p.speed,
                        settings.bound_tolerance,
                        &mut work,
                    )?
                });
            }
            (false, Some(lo)) => {
                let hi = crossing(
                    &motion,
                    points[k - 1].speed,
                    p.speed,
                    settings.bound_tolerance,
                    &mut work,
                )?;
                stable_ranges.push((lo, hi));
                start = None;
            }
            _ => {}
        }
    }
    if let (Some(lo), Some(last)) = (start, points.last()) {
        stable_ranges.push((lo, last.speed));
    }
    let (first, last) = (
        points.first().map_or(f64::NAN, |p| p.speed),
        points.last().map_or(f64::NAN, |p| p.speed),
    );
    let mut ranges = Vec::new();
    for &(lo, hi) in &stable_ranges {
        let kind = |v: f64, edge: f64, work: &mut Vec<f64>| {
            if v == edge {
                Ok(Crossing::GridEdge)
            } else {
                crossing_kind(&motion, v, work)
            }
        };
        ranges.push(StableRange {
            lo,
            hi,
            lo_crossing: kind(lo, first, &mut work)?,
            hi_crossing: kind(hi, last, &mut work)?,
        });
    }
    let weave_speed = ranges
        .first()
        .filter(|r| r.lo_crossing == Crossing::Oscillatory)
        .map(|r| r.lo);
    let capsize_speed = ranges
        .first()
        .filter(|r| r.hi_crossing == Crossing::Real)
        .map(|r| r.hi);
    Ok(SteadyResult {
        ranges,
        weave_speed,
        capsize_speed,
        model: model.name().to_string(),
        modes: motion.mode_names.clone(),
        speed_state: motion.speed_state.clone(),
        verdict: if stable_ranges.is_empty() {
            SteadyVerdict::NowhereStable
        } else {
            SteadyVerdict::SelfStable
        },
        points,
        stable_ranges,
    })
}

impl SteadyResult {
    /// One row per speed: the real and imaginary part of each eigenvalue.
    pub fn csv(&self) -> String {
        let k = self.points.first().map_or(0, |p| p.eigenvalues.len());
        let mut header = vec!["speed".to_string()];
        for i in 1..=k {
            header.push(format!("re{i}"));
            header.push(format!("im{i}"));
        }
        let mut out = header.join(",") + "\n";
        for p in &self.points {
            let mut row = vec![format!("{}", p.speed)];
            for (re, im) in &p.eigenvalues {
                row.push(format!("{re}"));
                row.push(format!("{im}"));
            }
            out += &(row.join(",") + "\n");
        }
        out
    }

    /// The eigenvalues followed by continuity from speed to speed (each new eigenvalue joins
    /// the nearest unclaimed branch), so that a mode keeps its curve where real parts cross.
    pub fn branches(&self) -> Vec<Vec<(f64, f64)>> {
        let Some(first) = self.points.first() else {
            return Vec::new();
        };
        let mut branches: Vec<Vec<(f64, f64)>> =
            first.eigenvalues.iter().map(|e| vec![*e]).collect();
        for p in &self.points[1..] {
            let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
            for (b, branch) in branches.iter().enumerate() {
                let last = branch[branch.len() - 1];
                for (e, ev) in p.eigenvalues.iter().enumerate() {
                    pairs.push((((ev.0 - last.0).powi(2) + (ev.1 - last.1).powi(2)), b, e));
                }
            }
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (mut taken_b, mut taken_e) = (
                vec![false; branches.len()],
                vec![false; p.eigenvalues.len()],
            );
            let mut next = vec![None; branches.len()];
            for (_, b, e) in pairs {
                if !taken_b[b] && !taken_e[e] {
                    taken_b[b] = true;
                    taken_e[e] = true;
                    next[b] = Some(p.eigenvalues[e]);
                }
            }
            for (branch, value) in branches.iter_mut().zip(next) {
                branch.push(value.unwrap_or((f64::NAN, f64::NAN)));
            }
        }
        branches
    }

    /// The classic plot: the real part of each eigenvalue branch and the largest imaginary
    /// part against speed.
    pub fn figure(&self) -> Figure {
        let speeds: Vec<f64> = self.points.iter().map(|p| p.speed).collect();
        let mut curves: Vec<Curve> = self
            .branches()
            .iter()
            .enumerate()
            .map(|(i, branch)| Curve {
                name: format!("Re λ{}", i + 1),
                points: speeds.iter().zip(branch).map(|(v, e)| (*v, e.0)).collect(),
            })
            .collect();
        curves.push(Curve {
            name: "max |Im λ|".into(),
            points: self
                .points
                .iter()
                .map(|p| {
                    (
                        p.speed,
                        p.eigenvalues.iter().fold(0.0, |m: f64, e| m.max(e.1.abs())),
                    )
                })
                .collect(),
        });
        let ranges: Vec<String> = self
            .stable_ranges
            .iter()
            .map(|(a, b)| format!("{a:.4}–{b:.4} m/s"))
            .collect();
        let title = match self.verdict {
            SteadyVerdict::SelfStable => format!(
                "{}: eigenvalues vs speed, self-stable {}",
                self.model,
                ranges.join(", ")
            ),
            SteadyVerdict::NowhereStable => {
                format!("{}: eigenvalues vs speed, nowhere self-stable", self.model)
            }
        };
        Figure::Line(LineChart::new(
            &title,
            "speed v [m/s]",
            "eigenvalue [1/s]",
            (900, 560),
            curves,
        ))
    }

    /// eigenvalues.csv, eigenvalues.svg/.png and steady.json.
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.text("eigenvalues.csv", self.csv());
        f.figure("eigenvalues.svg", &self.figure())?;
        f.json("steady.json", self);
        Ok(f)
    }

    /// The summary printed by the CLI.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{}: eigenvalues of {} about straight running, {} speeds {}…{} m/s\n",
            self.model,
            self.modes.join(", "),
            self.points.len(),
            self.points.first().map_or(0.0, |p| p.speed),
            self.points.last().map_or(0.0, |p| p.speed),
        );
        match self.verdict {
            SteadyVerdict::SelfStable => {
                for (a, b) in &self.stable_ranges {
                    s += &format!(
                        "  self-stable from {a:.14} to {b:.14} m/s (largest real part < 0)\n"
                    );
                }
            }
            SteadyVerdict::NowhereStable => {
                s += "  nowhere self-stable on the grid (largest real part ≥ 0 at every speed)\n"
            }
        }
        s
    }
}
