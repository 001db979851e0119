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

use nalgebra::{Complex, DMatrix, DVector, Matrix4, Schur};
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
        Ok(Self { speed, modes, a, b })
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

    /// A + b K.
    pub fn closed_loop_matrix(&self, g: &SteerGains) -> DMatrix<f64> {
        let k = g.row();
        let mut m = self.a.clone();
        for i in 0..4 {
            for (j, kj) in k.iter().enumerate() {
                m[(i, j)] += self.b[i] * kj;
            }
        }
        m
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
        let k = g.row();
        let m = Matrix4::from_fn(|i, j| self.a[(i, j)] + self.b[i] * k[j]);
        if m.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let schur = Schur::try_new(m, f64::EPSILON, 10_000)?;
        let abscissa = schur
            .complex_eigenvalues()
            .iter()
            .fold(f64::NEG_INFINITY, |a, e| a.max(e.re));
        abscissa.is_finite().then_some(abscissa)
    }

    /// ∂L(jω)/∂k_j for each gain: −e_jᵀ (jωI − A)⁻¹ b (`None` at a pole on the axis). L is
    /// linear in the gains, L = Σ k_j basis_j, which is what the tuner's convex steps use.
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
        Some(std::array::from_fn(|j| -x[j]))
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
