//! The convex–concave procedure of Hast, Åström, Bernhardsson and Boyd ("PID design by convex-
//! concave optimization", ECC 2013) for margin constraints on the pitch loop.
//!
//! The loop is linear in the gains, L(jω) = Σ_j k_j φ_j(jω), and each requirement says L(jω)
//! stays out of a disk {|L − c| < r}. That set is non-convex, but at the current gains k⁰,
//! with n = (L⁰ − c)/|L⁰ − c|, the half-plane Re[n̄ (L − c)] ≥ r lies inside it (|z| ≥ Re n̄z),
//! and is linear in k. So each step solves a convex problem (Clarabel) whose solution is
//! feasible for the true constraints on the grid, and the objective improves monotonically.
//! Phase 1 (when the start violates the spec) minimises a common slack σ on those
//! half-planes, Re[n̄ (L − c)] ≥ r (1 − σ); phase 2 optimises the objective with σ = 0.
//!
//! Because every iterate's segment to the next satisfies the half-planes of the step, the
//! Nyquist curve never crosses a forbidden disk (which contains −1) on the way, so a stabilising
//! start stays stabilising — up to the grid, which is why the tuner verifies independently.

use nalgebra::Complex;

use super::qp::{solve, SubOutcome, Subproblem};
use crate::linear::disk::Disk;
use crate::linear::pitch::{LoopOptions, PidGains, PitchLoop};

/// What the tuner optimises once the spec holds.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Closest gains to a target (scaled least squares): `--target Kp,Kd`.
    Target(PidGains),
    /// Smallest gains (scaled 2-norm) meeting the spec: least control effort and noise
    /// amplification; the default for PD.
    MinGain,
    /// Largest integral gain, Hast et al.'s load-disturbance criterion; the default for PID.
    MaxIntegral,
    /// Largest proportional gain (stiffness against constant disturbances).
    MaxProportional,
}

/// The discretised design problem in scaled variables x_j = k_j / s_j, for any loop whose
/// return ratio is linear in its gains, L(jω) = Σ_j k_j φ_j(jω).
pub(crate) struct Design {
    /// Which PID gain each variable is (0 = Kp, 1 = Ki, 2 = Kd); for another loop the
    /// variable's own index.
    vars: Vec<usize>,
    /// Scale s_j of each variable.
    scale: Vec<f64>,
    /// Per frequency, s_j φ_j (lag and delay included) for each variable.
    basis: Vec<Vec<Complex<f64>>>,
    /// Scaled lower bounds.
    pub lower: Vec<f64>,
    /// Scaled upper bounds.
    pub upper: Vec<f64>,
}

/// Index of Kp among the design variables (always the first).
pub(crate) const KP: usize = 0;

impl Design {
    /// Lays the grid (`points_per_decade` over [1e-3, 1e3] ω_ref, widened to 30/τ and 30/T,
    /// plus DC for PD) and the gain scales s_j = 1/|φ_j(jω_ref)|, ω_ref the largest plant pole.
    /// An undamped plant (a pendulum hanging below its hinge) can have that pole on the
    /// imaginary axis, where φ_j is infinite: the scales then come from 2ω_ref or ω_ref/2
    /// (they only condition the problem; any frequency off the poles serves).
    pub fn new(
        lp: &PitchLoop,
        opts: &LoopOptions,
        pid: bool,
        points_per_decade: usize,
        upper: f64,
    ) -> Option<Self> {
        let w_ref = lp
            .plant()
            .poles()
            .ok()?
            .iter()
            .map(|p| p.norm())
            .fold(0.0, f64::max);
        let w_ref = if w_ref > 0.0 { w_ref } else { 1.0 };
        let b_ref = [1.0, 2.0, 0.5]
            .iter()
            .find_map(|k| lp.gain_basis(0.0, k * w_ref))?;
        let pid_scale = [
            1.0 / b_ref.p.norm(),
            1.0 / b_ref.i?.norm(),
            1.0 / b_ref.d.norm(),
        ];
        let vars: Vec<usize> = if pid { vec![0, 1, 2] } else { vec![0, 2] };
        let scale: Vec<f64> = vars.iter().map(|&j| pid_scale[j]).collect();
        let mut w_hi = 1e3 * w_ref;
        for t in [opts.lag, opts.delay] {
            if t > 0.0 {
                w_hi = w_hi.max(30.0 / t);
            }
        }
        let mut grid = crate::linear::freq::log_grid(1e-3 * w_ref, w_hi, points_per_decade);
        if !pid {
            grid.insert(0, 0.0);
        }
        let basis = grid
            .iter()
            .filter_map(|&w| {
                let b = lp.gain_basis(opts.lag, w)?;
                let h = Complex::from_polar(1.0, -w * opts.delay);
                vars.iter()
                    .zip(&scale)
                    .map(|(&j, s)| match j {
                        0 => Some(b.p * h * *s),
                        1 => b.i.map(|i| i * h * *s),
                        _ => Some(b.d * h * *s),
                    })
                    .collect::<Option<Vec<_>>>()
            })
            .collect();
        let n = vars.len();
        Some(Self {
            vars,
            scale,
            basis,
            lower: vec![0.0; n],
            upper: vec![upper; n],
        })
    }

    /// A design of `basis` (per frequency, φ_j(jω) of each gain, unscaled), with the gains
    /// scaled by `scale` and bounded by `lower` ≤ k ≤ `upper` (unscaled).
    pub fn from_basis(
        basis: Vec<Vec<Complex<f64>>>,
        scale: Vec<f64>,
        lower: &[f64],
        upper: &[f64],
    ) -> Self {
        let basis = basis
            .into_iter()
            .map(|row| row.iter().zip(&scale).map(|(b, s)| b * *s).collect())
            .collect();
        Self {
            vars: (0..scale.len()).collect(),
            lower: lower.iter().zip(&scale).map(|(l, s)| l / s).collect(),
            upper: upper.iter().zip(&scale).map(|(u, s)| u / s).collect(),
            scale,
            basis,
        }
    }

    /// The gains k_j = s_j x_j of scaled variables.
    pub fn values(&self, x: &[f64]) -> Vec<f64> {
        x.iter().zip(&self.scale).map(|(v, s)| v * s).collect()
    }

    /// The scaled variables x_j = k_j / s_j of gains.
    pub fn scaled_values(&self, k: &[f64]) -> Vec<f64> {
        k.iter().zip(&self.scale).map(|(v, s)| v / s).collect()
    }

    /// Bounds Kp from above by `kp_max` (the effort bound; never below the lower bound).
    pub fn bound_kp(&mut self, kp_max: f64) {
        let x = (kp_max / self.scale[0]).max(self.lower[KP]);
        self.upper[KP] = self.upper[KP].min(x);
    }

    /// Number of variables.
    pub fn len(&self) -> usize {
        self.vars.len()
    }

    /// PID gains of scaled variables.
    pub fn gains(&self, x: &[f64]) -> PidGains {
        let mut k = [0.0; 3];
        for ((&j, v), s) in self.vars.iter().zip(x).zip(&self.scale) {
            k[j] = v * s;
        }
        PidGains {
            kp: k[0],
            ki: k[1],
            kd: k[2],
        }
    }

    /// Scaled variables of PID gains.
    pub fn scaled(&self, g: &PidGains) -> Vec<f64> {
        let k = [g.kp, g.ki, g.kd];
        self.vars
            .iter()
            .zip(&self.scale)
            .map(|(&j, s)| k[j] / s)
            .collect()
    }

    fn response(&self, at: &[Complex<f64>], x: &[f64]) -> Complex<f64> {
        at.iter().zip(x).map(|(b, v)| b * *v).sum()
    }

    /// Largest relative intrusion max (r − |L − c|)/r over grid and disks (≤ 0: feasible).
    pub fn violation(&self, x: &[f64], disks: &[Disk]) -> f64 {
        let mut worst = f64::NEG_INFINITY;
        for at in &self.basis {
            let l = self.response(at, x);
            for d in disks {
                let r = d.radius.max(1e-12);
                worst = worst.max((r - (l - d.centre).norm()) / r);
            }
        }
        worst
    }

    /// The half-plane constraints at x: rows a, right-hand sides, and the radius of each (for
    /// the slack column).
    fn linearise(&self, x: &[f64], disks: &[Disk]) -> (Vec<Vec<f64>>, Vec<f64>, Vec<f64>) {
        let mut rows = Vec::with_capacity(self.basis.len() * disks.len());
        let mut rhs = Vec::with_capacity(rows.capacity());
        let mut radius = Vec::with_capacity(rows.capacity());
        for at in &self.basis {
            let l = self.response(at, x);
            for d in disks {
                let n = exit_direction(l, d);
                rows.push(at.iter().map(|b| (n.conj() * b).re).collect());
                rhs.push(d.radius + d.centre * n.re);
                radius.push(d.radius.max(1e-12));
            }
        }
        (rows, rhs, radius)
    }
}

/// The unit direction n of the half-plane Re[n̄ (L − c)] ≥ r that replaces the disk at the
/// point L⁰ (any unit n gives a half-plane outside the disk). Outside the disk: away from its
/// centre, the tangent half-plane at the nearest boundary point. Inside it: away from the
/// critical point −1 (which every requirement disk contains), the exit that does not carry the
/// Nyquist curve across −1; leaving the other way would destabilise the loop, so the
/// convex–concave step stalled there (a 60° disk phase margin, whose disk holds the study
/// gains' DC point near its centre, was reported infeasible).
fn exit_direction(l: Complex<f64>, d: &Disk) -> Complex<f64> {
    let unit = |z: Complex<f64>| (z.norm() > 0.0).then(|| z / z.norm());
    let off = l - d.centre;
    let from_critical = unit(l + 1.0).filter(|_| off.norm() < d.radius);
    from_critical
        .or_else(|| unit(off))
        .unwrap_or(Complex::new(1.0, 0.0))
}

/// How phase 1 ended.
pub(crate) enum Phase1 {
    /// Gains meeting the (grid) constraints.
    Feasible(Vec<f64>),
    /// No further progress with the slack still positive: the spec looks infeasible from here.
    Stalled,
    /// The caller cancelled the run.
    Interrupted,
}

/// Phase 1: drive the common slack σ on the `disks` of the spec to zero while keeping the
/// `floor` disks (a weaker version of the spec that the start already meets, each containing
/// −1) as hard constraints: the Nyquist curve then never crosses −1, so a stabilising start
/// stays stabilising (a slack alone would let it collapse to L ≡ 0, outside every disk but
/// unstable).
pub(crate) fn phase1(
    design: &Design,
    x0: &[f64],
    disks: &[Disk],
    floor: &[Disk],
    max_iter: usize,
    stop: &dyn Fn() -> bool,
) -> Phase1 {
    let n = design.len();
    let mut x = x0.to_vec();
    for _ in 0..max_iter {
        if design.violation(&x, disks) <= 0.0 {
            return Phase1::Feasible(x);
        }
        if stop() {
            return Phase1::Interrupted;
        }
        let (mut rows, mut rhs, radius) = design.linearise(&x, disks);
        for (row, r) in rows.iter_mut().zip(&radius) {
            row.push(*r);
        }
        let (hard, hard_rhs, _) = design.linearise(&x, floor);
        rows.extend(hard.into_iter().map(|mut r| {
            r.push(0.0);
            r
        }));
        rhs.extend(hard_rhs);
        let mut q = vec![0.0; n + 1];
        q[n] = 1.0;
        let mut lower = design.lower.clone();
        lower.push(0.0);
        let mut upper = design.upper.clone();
        upper.push(1e6);
        let sub = Subproblem {
            p_diag: vec![0.0; n + 1],
            q,
            rows,
            rhs,
            lower,
            upper,
        };
        let SubOutcome::Solved(sol) = solve(&sub) else {
            return Phase1::Stalled;
        };
        let next = sol[..n].to_vec();
        let step = next
            .iter()
            .zip(&x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        x = next;
        if sol[n] > 1e-7 && step <= 1e-9 * (1.0 + x.iter().fold(0.0_f64, |m, v| m.max(v.abs()))) {
            return Phase1::Stalled;
        }
    }
    if design.violation(&x, disks) <= 0.0 {
        Phase1::Feasible(x)
    } else {
        Phase1::Stalled
    }
}

/// What phase 2 optimises, in the design's scaled variables.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Goal {
    /// Closest to these scaled variables (least squares).
    Target(Vec<f64>),
    /// Smallest scaled 2-norm.
    MinGain,
    /// Largest value of this variable.
    Max(usize),
}

impl Objective {
    /// The goal of a PID design.
    pub(crate) fn goal(&self, design: &Design) -> Goal {
        match self {
            Objective::Target(t) => Goal::Target(design.scaled(t)),
            Objective::MinGain => Goal::MinGain,
            Objective::MaxIntegral | Objective::MaxProportional => {
                let which = if matches!(self, Objective::MaxIntegral) {
                    1
                } else {
                    0
                };
                Goal::Max(design.vars.iter().position(|&j| j == which).unwrap_or(0))
            }
        }
    }
}

/// How phase 2 ended.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Phase2End {
    /// Steps became negligible.
    Converged,
    /// The iteration budget ran out (the gains are still feasible).
    IterationLimit,
    /// A subproblem failed; the last feasible gains are kept.
    SolverFailed(String),
    /// The caller cancelled the run.
    Interrupted,
}

/// Phase 2: optimise the goal from feasible x0. Returns the gains, how it ended and the
/// number of subproblems solved.
pub(crate) fn phase2(
    design: &Design,
    x0: &[f64],
    disks: &[Disk],
    goal: &Goal,
    max_iter: usize,
    stop: &dyn Fn() -> bool,
) -> (Vec<f64>, Phase2End, usize) {
    let n = design.len();
    let (p_diag, q) = match goal {
        Goal::Target(ts) => (vec![1.0; n], ts.iter().map(|v| -v).collect()),
        Goal::MinGain => (vec![1.0; n], vec![0.0; n]),
        Goal::Max(which) => (
            vec![0.0; n],
            (0..n)
                .map(|v| if v == *which { -1.0 } else { 0.0 })
                .collect(),
        ),
    };
    let mut x = x0.to_vec();
    for it in 1..=max_iter {
        if stop() {
            return (x, Phase2End::Interrupted, it);
        }
        let (rows, rhs, _) = design.linearise(&x, disks);
        let sub = Subproblem {
            p_diag: p_diag.clone(),
            q: q.clone(),
            rows,
            rhs,
            lower: design.lower.clone(),
            upper: design.upper.clone(),
        };
        let next = match solve(&sub) {
            SubOutcome::Solved(next) => next,
            SubOutcome::Failed(why) => return (x, Phase2End::SolverFailed(why), it),
        };
        let step = next
            .iter()
            .zip(&x)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let size = 1.0 + next.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        x = next;
        if step <= 1e-7 * size {
            return (x, Phase2End::Converged, it);
        }
    }
    (x, Phase2End::IterationLimit, max_iter)
}
