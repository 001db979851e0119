//! A two-wheeler's steer loop at a steady speed: the lean-and-steer dynamics linearised about
//! straight running, ẋ = A x + b T_δ on x = (φ, δ, φ̇, δ̇) (the modes the IR's steady motion
//! names, in its order: lean, steer, lean rate, steer rate), closed by the steer-torque law
//!
//! ```text
//! T_δ = k_φ φ + k_δ δ + k_φ̇ φ̇ + k_δ̇ δ̇
//! ```
//!
//! (Åström, Klein and Lennartsson's "steer into the fall": with the benchmark bicycle's signs,
//! φ > 0 a lean to the right and T_δ > 0 a torque turning the handlebar to the right, k_φ > 0
//! steers towards the lean.) Sign convention as the pitch loop's: the law as written is
//! positive feedback, so in the negative-feedback convention the margins are defined in, the
//! return ratio broken at the steer-torque input is L(s) = −K (sI − A)⁻¹ b and the closed-loop
//! matrix is A + b K.
//!
//! With a rate filter of time constant τ the law reads the rates through 1/(τs + 1), as a
//! real sensor or a rider's neuromuscular lag would: two more states r = (r_φ̇, r_δ̇),
//! ṙ = ((φ̇, δ̇) − r)/τ, and T_δ = k_φ φ + k_δ δ + k_φ̇ r_φ̇ + k_δ̇ r_δ̇. The closed loop is then
//! 6 × 6 and the rate gains' terms of L carry the factor 1/(jωτ + 1); L stays linear in the
//! gains, so the tuner's convex steps hold unchanged.

use std::ops::IndexMut;

use nalgebra::{Complex, DMatrix, DVector, Matrix4, Matrix6, Schur};
use serde::{Deserialize, Serialize};

use super::error::{check_finite, LinearError};
use super::margins::{loop_margins, GridOptions, Margins};
use super::modes::{eigenvalues, spectral_abscissa};

/// The input the steer loop drives.
pub const STEER_INPUT: &str = "T_delta";

/// Gains of the steer-torque law, in the order of the modes (lean, steer, lean rate, steer
/// rate). Units for the bicycle: N m/rad, N m/rad, N m s/rad, N m s/rad.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SteerGains {
    /// On the lean angle φ.
    pub k_phi: f64,
    /// On the steer angle δ.
    pub k_delta: f64,
    /// On the lean rate φ̇.
    pub k_phi_dot: f64,
    /// On the steer rate δ̇.
    pub k_delta_dot: f64,
}

impl SteerGains {
    /// The gains' names, in the order of [`row`](Self::row).
    pub const NAMES: [&'static str; 4] = ["k_phi", "k_delta", "k_phi_dot", "k_delta_dot"];

    /// K as a row over (φ, δ, φ̇, δ̇).
    pub fn row(&self) -> [f64; 4] {
        [self.k_phi, self.k_delta, self.k_phi_dot, self.k_delta_dot]
    }

    /// The gains of a row over (φ, δ, φ̇, δ̇).
    pub fn from_row(k: [f64; 4]) -> Self {
        Self {
            k_phi: k[0],
            k_delta: k[1],
            k_phi_dot: k[2],
            k_delta_dot: k[3],
        }
    }

    /// Rejects NaN and infinite gains.
    pub fn check(&self) -> Result<(), LinearError> {
        check_finite("steer gains", self.row().iter())
    }
}

/// The lean-and-steer plant at one speed with the steer-torque input.
#[derive(Debug, Clone, PartialEq)]
pub struct SteerLoop {
    speed: f64,
    modes: Vec<String>,
    a: DMatrix<f64>,
    b: DVector<f64>,
    /// τ of the rates' first-order filter [s]; `None`: the rates are read directly.
    rate_filter: Option<f64>,
}

/// Which entries of the rates' filter the law reads: the rates are modes 2 and 3 (φ̇, δ̇).
const RATES: [usize; 2] = [2, 3];

/// The closed loop of ẋ = A x + b T_δ (any state, n × n) under the steer law acting on the
/// states `modes` (indices of φ, δ, φ̇, δ̇ in x): A + b K, or with a rate filter of time
/// constant τ the (n + 2)-square matrix on (x, r_φ̇, r_δ̇)
///
/// ```text
/// [ A + b K_angles   b k_φ̇   b k_δ̇ ]
/// [ e_φ̇ᵀ/τ           −1/τ     0     ]
/// [ e_δ̇ᵀ/τ            0      −1/τ   ]
/// ```
///
/// The one formula for the lean-and-steer loop ([`SteerLoop`]) and every state's closed loop
/// (`twv linearize --steer-gains`).
pub fn steer_closed_loop(
    a: &DMatrix<f64>,
    b: &[f64],
    modes: [usize; 4],
    gains: &SteerGains,
    rate_filter: Option<f64>,
) -> DMatrix<f64> {
    let n = a.nrows();
    let extra = if rate_filter.is_some() { 2 } else { 0 };
    let mut m = DMatrix::zeros(n + extra, n + extra);
    write_closed_loop(&mut m, a, b, modes, gains, rate_filter);
    m
}

/// [`steer_closed_loop`] written into `m` (zero, of the closed loop's size): a heap or a stack
/// matrix alike.
fn write_closed_loop<M: IndexMut<(usize, usize), Output = f64>>(
    m: &mut M,
    a: &DMatrix<f64>,
    b: &[f64],
    modes: [usize; 4],
    gains: &SteerGains,
    rate_filter: Option<f64>,
) {
    let n = a.nrows();
    for i in 0..n {
        for j in 0..n {
            m[(i, j)] = a[(i, j)];
        }
    }
    // Where each gain reads: its mode, or a rate's filter state.
    let read = |j: usize| match (rate_filter, RATES.iter().position(|&r| r == j)) {
        (Some(_), Some(f)) => n + f,
        _ => modes[j],
    };
    for (j, kj) in gains.row().iter().enumerate() {
        for (i, bi) in b.iter().enumerate() {
            m[(i, read(j))] += bi * kj;
        }
    }
    if let Some(tau) = rate_filter {
        for (f, &r) in RATES.iter().enumerate() {
            m[(n + f, modes[r])] = 1.0 / tau;
            m[(n + f, n + f)] = -1.0 / tau;
        }
    }
}

/// The closed loop's eigenvalues.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerClosedLoop {
    /// Eigenvalues of A + b K.
    pub eigenvalues: Vec<Complex<f64>>,
    /// Their largest real part.
    pub spectral_abscissa: f64,
    /// Every eigenvalue has Re < 0.
    pub stable: bool,
}

/// Closed-loop eigenvalues and margins at the steer-torque input.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerAnalysis {
    /// The gains analysed.
    pub gains: SteerGains,
    /// Eigenvalues of the closed loop.
    pub closed_loop: SteerClosedLoop,
    /// Gain, phase, delay and disk margins of L(s) = −K (sI − A)⁻¹ b.
    pub margins: Margins,
}

impl SteerLoop {
    /// The loop of the plant ẋ = A x + B u (A on the four modes, B with one column per input)
    /// driven through input column `input`.
    pub fn new(
        speed: f64,
        modes: Vec<String>,
        a: DMatrix<f64>,
        b: &DMatrix<f64>,
        input: usize,
    ) -> Result<Self, LinearError> {
        if a.nrows() != 4 || a.ncols() != 4 || modes.len() != 4 {
            return Err(LinearError::Dimension {
                what: "lean-and-steer modes",
                expected: 4,
                got: modes.len(),
            });
        }
        if input >= b.ncols() || b.nrows() != 4 {
            return Err(LinearError::Dimension {
                what: "steer input column",
                expected: b.ncols(),
                got: input,
            });
        }
        check_finite("the lean-and-steer Jacobian", a.iter().chain(b.iter()))?;
        let b = b.column(input).into_owned();
        if b.iter().all(|v| *v == 0.0) {
            return Err(LinearError::ZeroInput);
        }
        Ok(Self {
            speed,
            modes,
            a,
            b,
            rate_filter: None,
        })
    }

    /// The same loop with the law reading the rates through a first-order filter of time
    /// constant `tau` [s] (`None`: unfiltered).
    pub fn with_rate_filter(mut self, tau: Option<f64>) -> Result<Self, LinearError> {
        if let Some(t) = tau {
            check_finite("the rate filter's time constant", [t].iter())?;
            if t <= 0.0 {
                return Err(LinearError::NonPositive {
                    what: "rate filter time constant",
                    value: t,
                });
            }
        }
        self.rate_filter = tau;
        Ok(self)
    }

    /// τ of the rate filter [s], if the law has one.
    pub fn rate_filter(&self) -> Option<f64> {
        self.rate_filter
    }

    /// The speed [m/s].
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// The modes, in the order of the gains.
    pub fn modes(&self) -> &[String] {
        &self.modes
    }

    /// A on the modes.
    pub fn a(&self) -> &DMatrix<f64> {
        &self.a
    }

    /// b, the steer torque's column on the modes.
    pub fn b(&self) -> &DVector<f64> {
        &self.b
    }

    /// Eigenvalues of the open loop (the uncontrolled bicycle at this speed).
    pub fn open_loop_eigenvalues(&self) -> Result<Vec<Complex<f64>>, LinearError> {
        eigenvalues(&self.a)
    }

    /// A + b K (6 × 6 with the rate filter's states, see [`steer_closed_loop`]).
    pub fn closed_loop_matrix(&self, g: &SteerGains) -> DMatrix<f64> {
        steer_closed_loop(
            &self.a,
            self.b.as_slice(),
            [0, 1, 2, 3],
            g,
            self.rate_filter,
        )
    }

    /// The closed loop's eigenvalues.
    pub fn closed_loop(&self, g: &SteerGains) -> Result<SteerClosedLoop, LinearError> {
        g.check()?;
        let eigenvalues = eigenvalues(&self.closed_loop_matrix(g))?;
        if eigenvalues
            .iter()
            .any(|e| !(e.re.is_finite() && e.im.is_finite()))
        {
            return Err(LinearError::NonFinite {
                what: "closed-loop poles (the gains are too large for double precision)",
            });
        }
        let spectral_abscissa = spectral_abscissa(&eigenvalues);
        Ok(SteerClosedLoop {
            stable: spectral_abscissa < 0.0,
            spectral_abscissa,
            eigenvalues,
        })
    }

    /// The closed loop's spectral abscissa (largest real part of the eigenvalues of A + b K),
    /// on the stack: what a map asks of each of its cells, without the eigenvalues' vector
    /// (`None` when the Schur iteration does not converge or the result is not finite).
    pub fn closed_loop_abscissa(&self, g: &SteerGains) -> Option<f64> {
        let largest = |e: &[Complex<f64>]| e.iter().fold(f64::NEG_INFINITY, |a, e| a.max(e.re));
        // The closed loop on the stack, at the size it has.
        macro_rules! on_stack {
            ($matrix:ty) => {{
                let mut m = <$matrix>::zeros();
                let modes = [0, 1, 2, 3];
                write_closed_loop(
                    &mut m,
                    &self.a,
                    self.b.as_slice(),
                    modes,
                    g,
                    self.rate_filter,
                );
                if m.iter().any(|v| !v.is_finite()) {
                    return None;
                }
                let schur = Schur::try_new(m, f64::EPSILON, 10_000)?;
                largest(schur.complex_eigenvalues().as_slice())
            }};
        }
        let abscissa = match self.rate_filter {
            None => on_stack!(Matrix4<f64>),
            Some(_) => on_stack!(Matrix6<f64>),
        };
        abscissa.is_finite().then_some(abscissa)
    }

    /// ∂L(jω)/∂k_j for each gain: −e_jᵀ (jωI − A)⁻¹ b, the rates' two times 1/(jωτ + 1)
    /// with a rate filter (`None` at a pole on the axis). L is linear in the gains,
    /// L = Σ k_j basis_j, which is what the tuner's convex steps use.
    pub fn basis(&self, w: f64) -> Option<[Complex<f64>; 4]> {
        let m = DMatrix::from_fn(4, 4, |i, j| {
            let diagonal = if i == j {
                Complex::new(0.0, w)
            } else {
                Complex::new(0.0, 0.0)
            };
            diagonal - Complex::new(self.a[(i, j)], 0.0)
        });
        let rhs = DVector::from_fn(4, |i, _| Complex::new(self.b[i], 0.0));
        let x = m.lu().solve(&rhs)?;
        if x.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            return None;
        }
        let filter = self.rate_filter.map_or(Complex::new(1.0, 0.0), |tau| {
            1.0 / Complex::new(1.0, w * tau)
        });
        Some(std::array::from_fn(|j| {
            if RATES.contains(&j) {
                -x[j] * filter
            } else {
                -x[j]
            }
        }))
    }

    /// L(jω) of the gains.
    pub fn response(&self, g: &SteerGains, w: f64) -> Option<Complex<f64>> {
        let basis = self.basis(w)?;
        Some(basis.iter().zip(g.row()).map(|(b, k)| b * k).sum())
    }

    /// The loop's characteristic frequencies (open- and closed-loop pole magnitudes), around
    /// which the margins' frequency grid is laid.
    pub fn scales(&self, closed: &SteerClosedLoop) -> Result<Vec<f64>, LinearError> {
        let mut s: Vec<f64> = self
            .open_loop_eigenvalues()?
            .iter()
            .map(|p| p.norm())
            .collect();
        s.extend(closed.eigenvalues.iter().map(|p| p.norm()));
        s.extend(self.rate_filter.map(|tau| 1.0 / tau));
        Ok(s)
    }

    /// Closed-loop eigenvalues and the margins at the steer-torque input.
    pub fn analyse(&self, g: &SteerGains) -> Result<SteerAnalysis, LinearError> {
        let closed_loop = self.closed_loop(g)?;
        let grid = GridOptions::around(&self.scales(&closed_loop)?);
        let l0 = |w: f64| self.response(g, w);
        let margins = loop_margins(&l0, 0.0, closed_loop.stable, &grid);
        Ok(SteerAnalysis {
            gains: *g,
            closed_loop,
            margins,
        })
    }
}
