//! The hand model: an independent, closed-form derivation of `vehicle8`, `vehicle7` and `segway7`.
//!
//! This is the second route used by `twv audit`. It shares nothing with the CasADi derivation or
//! the IR: every term of M(q), C(q,p) p, F(q) and Q(u) below was derived by hand (Kane's method /
//! Euler–Poincaré on SE(2), see `DERIVATION.md` next to this file) and written out as a formula.
//! The conventions are those of docs/src/conventions.md, so the audit can compare term by term.
//!
//! Every formula is written once, generically over [`scalar::Real`], and evaluated with `f64` for
//! values and with [`scalar::Dual`] for exact derivatives (Jacobians, Ṁ). ṗ = M⁻¹(Q − Cp − F) is a
//! small dense solve on the stack; nothing allocates.
//!
//! Deliberately wrong variants ([`Mistake`]) exist so that the audit's own tests can show that it
//! catches real derivation errors.

mod params;
pub mod scalar;
mod segway7;
mod vehicle7;
mod vehicle8;

pub use params::{VehicleParams, PARAM_NAMES};
pub use segway7::HandSegway7;
pub use vehicle7::HandVehicle7;
pub use vehicle8::HandVehicle8;

use scalar::{solve, Dual, Real};
use twv_model::ModelInfo;

/// A deliberate derivation error, for testing that the audit catches it. The correct model has
/// no mistake; each variant changes the equations of motion but leaves `energy` and `momentum`
/// the correct functions of the state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mistake {
    /// Drops the gyroscopic pair that substituting the no-side-slip constraint v_y = 0 into the
    /// Lagrangian loses: −m2 b sinΦ w_z² from the v_x row of Cp and +m2 b sinΦ v_x w_z from the
    /// w_z row. Both come from the lateral momentum m2 b sinΦ w_z of the leaning pendulum; their
    /// powers cancel (v_x·(−m2 b s w_z²) + w_z·(m2 b s v_x w_z) = 0), so this wrong model still
    /// conserves energy and only a term-by-term comparison finds it. Applied to every model
    /// (in vehicle8 the same pair is dropped from the unconstrained equations).
    DropGyroscopicPair,
    /// Flips the sign of the gravity term: F = (+m2 g b sinΦ, 0, …). The upright becomes stable,
    /// the hanging position unstable, and energy T + V is no longer conserved.
    FlipGravitySign,
}

/// The hand equations of one model, generic over the number type so that the same formulas give
/// values (`f64`) and exact derivatives ([`Dual`]). `NX = 4 + NS`: the state is the coordinates
/// q = (Φ, x, y, θ) followed by the `NS` quasi-velocities p, and Poincaré's form reads
/// M(q) ṗ + Cp(q,p) + F(q) = Q(q,u).
pub trait HandEquations<const NX: usize, const NU: usize, const NS: usize> {
    /// Names of the model, its states, inputs and parameters.
    fn model_info(&self) -> ModelInfo;
    /// Mass matrix M(q) (the Hessian of T in the speeds; symmetric).
    fn mass<S: Real>(&self, x: &[S; NX]) -> [[S; NS]; NS];
    /// All velocity terms C(q,p) p.
    fn velocity_terms<S: Real>(&self, x: &[S; NX]) -> [S; NS];
    /// Gravity generalized force F(q) (on the left-hand side).
    fn gravity_terms<S: Real>(&self, x: &[S; NX]) -> [S; NS];
    /// Generalized input forces Q(q, u).
    fn input_terms<S: Real>(&self, x: &[S; NX], u: &[S; NU]) -> [S; NS];
    /// q̇ = (Φ̇, ẋ, ẏ, θ̇) from the kinematics.
    fn qdot<S: Real>(&self, x: &[S; NX]) -> [S; 4];
    /// T + V computed body by body from the centroid velocities and angular velocities (not from
    /// M, so that ½ pᵀ M p = T is a check).
    fn energy_of<S: Real>(&self, x: &[S; NX]) -> S;
    /// Planar linear momentum (X, Y) and Z angular momentum about the inertial origin.
    fn momentum_of(&self, x: &[f64; NX]) -> [f64; 3];
}

/// ẋ = f(x, u): q̇ from the kinematics, ṗ = M⁻¹ (Q − Cp − F).
pub fn eval_f<E, S, const NX: usize, const NU: usize, const NS: usize>(
    e: &E,
    x: &[S; NX],
    u: &[S; NU],
) -> [S; NX]
where
    E: HandEquations<NX, NU, NS>,
    S: Real,
{
    let m = e.mass(x);
    let cp = e.velocity_terms(x);
    let fg = e.gravity_terms(x);
    let q = e.input_terms(x, u);
    let mut rhs = [S::cst(0.0); NS];
    for (i, r) in rhs.iter_mut().enumerate() {
        *r = q[i] - cp[i] - fg[i];
    }
    let pd = solve(m, rhs);
    let qd = e.qdot(x);
    let mut out = [S::cst(0.0); NX];
    for (o, v) in out.iter_mut().zip(qd.iter().chain(pd.iter())) {
        *o = *v;
    }
    out
}

/// Dual numbers with values `x` and derivative seeds `dir`.
pub fn seed<const N: usize>(x: &[f64; N], dir: &[f64; N]) -> [Dual; N] {
    let mut out = [Dual::default(); N];
    for (o, (v, d)) in out.iter_mut().zip(x.iter().zip(dir.iter())) {
        *o = Dual::new(*v, *d);
    }
    out
}

/// Constant dual numbers (zero derivative).
pub fn constant<const N: usize>(x: &[f64; N]) -> [Dual; N] {
    seed(x, &[0.0; N])
}

/// Ṁ = Σ ∂M/∂q_i q̇_i along the motion, exactly (dual numbers seeded with q̇).
pub fn mass_rate<E, const NX: usize, const NU: usize, const NS: usize>(
    e: &E,
    x: &[f64; NX],
) -> [[f64; NS]; NS]
where
    E: HandEquations<NX, NU, NS>,
{
    let qd = e.qdot(x);
    let mut dir = [0.0; NX];
    for (d, v) in dir.iter_mut().zip(qd.iter()) {
        *d = *v;
    }
    let m = e.mass(&seed(x, &dir));
    let mut out = [[0.0; NS]; NS];
    for (o, r) in out.iter_mut().zip(m.iter()) {
        for (oij, mij) in o.iter_mut().zip(r.iter()) {
            *oij = mij.d;
        }
    }
    out
}

/// dE/dt = ∇E · f(x, u), exactly (dual numbers seeded with ẋ).
pub fn energy_rate<E, const NX: usize, const NU: usize, const NS: usize>(
    e: &E,
    x: &[f64; NX],
    u: &[f64; NU],
) -> f64
where
    E: HandEquations<NX, NU, NS>,
{
    let xd = eval_f(e, x, u);
    e.energy_of(&seed(x, &xd)).d
}

/// Compressed-column pointers of a dense `N × N` pattern (`NP1 = N + 1` entries).
const fn dense_colind<const NP1: usize>() -> [usize; NP1] {
    let mut c = [0; NP1];
    let mut j = 0;
    while j < NP1 {
        c[j] = j * (NP1 - 1);
        j += 1;
    }
    c
}

/// Row indices of a dense `n × n` pattern in compressed-column order (`NN = n²` entries).
const fn dense_rows<const NN: usize>(n: usize) -> [usize; NN] {
    let mut r = [0; NN];
    let mut k = 0;
    while k < NN {
        r[k] = k % n;
        k += 1;
    }
    r
}

static COLIND8: [usize; 9] = dense_colind();
static ROWS8: [usize; 64] = dense_rows(8);
static COLIND7: [usize; 8] = dense_colind();
static ROWS7: [usize; 49] = dense_rows(7);

/// Implements `twv_model::Model` and `twv_model::Mechanical` for a hand model on top of its
/// [`HandEquations`]: values with `f64`, Jacobians and J·w with dual numbers (one pass per column
/// or per tangent vector). The sparse pattern is dense: the hand model makes no sparsity claims.
macro_rules! impl_model {
    ($ty:ty, $nx:literal, $nu:literal, $ns:literal, $colind:ident, $rows:ident) => {
        impl twv_model::Model<$nx, $nu> for $ty {
            fn info(&self) -> twv_model::ModelInfo {
                $crate::hand_model::HandEquations::<$nx, $nu, $ns>::model_info(self)
            }

            fn f(&self, x: &[f64; $nx], u: &[f64; $nu], out: &mut [f64; $nx]) {
                *out = $crate::hand_model::eval_f::<_, f64, $nx, $nu, $ns>(self, x, u);
            }

            fn jac_x(&self, x: &[f64; $nx], u: &[f64; $nu], out: &mut [[f64; $nx]; $nx]) {
                let ud = $crate::hand_model::constant(u);
                for j in 0..$nx {
                    let mut dir = [0.0; $nx];
                    dir[j] = 1.0;
                    let xd = $crate::hand_model::seed(x, &dir);
                    let fd = $crate::hand_model::eval_f::<_, _, $nx, $nu, $ns>(self, &xd, &ud);
                    for (row, v) in out.iter_mut().zip(fd.iter()) {
                        row[j] = v.d;
                    }
                }
            }

            fn jac_u(&self, x: &[f64; $nx], u: &[f64; $nu], out: &mut [[f64; $nu]; $nx]) {
                let xd = $crate::hand_model::constant(x);
                for j in 0..$nu {
                    let mut dir = [0.0; $nu];
                    dir[j] = 1.0;
                    let ud = $crate::hand_model::seed(u, &dir);
                    let fd = $crate::hand_model::eval_f::<_, _, $nx, $nu, $ns>(self, &xd, &ud);
                    for (row, v) in out.iter_mut().zip(fd.iter()) {
                        row[j] = v.d;
                    }
                }
            }

            fn jac_x_colind(&self) -> &[usize] {
                &$colind
            }

            fn jac_x_row(&self) -> &[usize] {
                &$rows
            }

            fn jac_x_sparse(&self, x: &[f64; $nx], u: &[f64; $nu], values: &mut [f64]) {
                let mut jac = [[0.0; $nx]; $nx];
                self.jac_x(x, u, &mut jac);
                // Dense CCS: column j occupies values[j*NX .. (j+1)*NX], rows in order.
                for (k, v) in values.iter_mut().enumerate().take($nx * $nx) {
                    *v = jac[k % $nx][k / $nx];
                }
            }

            fn f_jw<const K: usize>(
                &self,
                x: &[f64; $nx],
                u: &[f64; $nu],
                w: &[[f64; $nx]; K],
                f: &mut [f64; $nx],
                out: &mut [[f64; $nx]; K],
            ) {
                *f = $crate::hand_model::eval_f::<_, f64, $nx, $nu, $ns>(self, x, u);
                let ud = $crate::hand_model::constant(u);
                for (o, wk) in out.iter_mut().zip(w.iter()) {
                    let xd = $crate::hand_model::seed(x, wk);
                    let fd = $crate::hand_model::eval_f::<_, _, $nx, $nu, $ns>(self, &xd, &ud);
                    for (oi, v) in o.iter_mut().zip(fd.iter()) {
                        *oi = v.d;
                    }
                }
            }
        }

        impl twv_model::Mechanical<$nx, $nu, $ns> for $ty {
            fn mass_matrix(&self, x: &[f64; $nx], out: &mut [[f64; $ns]; $ns]) {
                *out = $crate::hand_model::HandEquations::<$nx, $nu, $ns>::mass(self, x);
            }
            fn cp(&self, x: &[f64; $nx], out: &mut [f64; $ns]) {
                *out = $crate::hand_model::HandEquations::<$nx, $nu, $ns>::velocity_terms(self, x);
            }
            fn gravity(&self, x: &[f64; $nx], out: &mut [f64; $ns]) {
                *out = $crate::hand_model::HandEquations::<$nx, $nu, $ns>::gravity_terms(self, x);
            }
            fn input_forces(&self, x: &[f64; $nx], u: &[f64; $nu], out: &mut [f64; $ns]) {
                *out = $crate::hand_model::HandEquations::<$nx, $nu, $ns>::input_terms(self, x, u);
            }
            fn energy(&self, x: &[f64; $nx]) -> f64 {
                $crate::hand_model::HandEquations::<$nx, $nu, $ns>::energy_of(self, x)
            }
            fn momentum(&self, x: &[f64; $nx]) -> [f64; 3] {
                $crate::hand_model::HandEquations::<$nx, $nu, $ns>::momentum_of(self, x)
            }
        }
    };
}

impl_model!(HandVehicle8, 8, 2, 4, COLIND8, ROWS8);
impl_model!(HandVehicle7, 7, 2, 3, COLIND7, ROWS7);
impl_model!(HandSegway7, 7, 2, 3, COLIND7, ROWS7);

/// State names shared with the IR (vehicle8).
const STATES8: [&str; 8] = ["phi", "x", "y", "theta", "w_y", "v_x", "v_y", "w_z"];
/// State names shared with the IR (vehicle7, segway7).
const STATES7: [&str; 7] = ["phi", "x", "y", "theta", "w_y", "v_x", "w_z"];

/// Planar kinematics of the frame A: (ẋ, ẏ) = R(θ) (v_x, v_y).
fn planar_velocity<S: Real>(theta: S, vx: S, vy: S) -> (S, S) {
    let (s, c) = (theta.sin(), theta.cos());
    (vx * c - vy * s, vx * s + vy * c)
}

/// A vector given in A components (a_x, a_y) expressed in N's horizontal components (X, Y).
fn a_to_n(theta: f64, ax: f64, ay: f64) -> [f64; 2] {
    let (s, c) = theta.sin_cos();
    [ax * c - ay * s, ax * s + ay * c]
}
