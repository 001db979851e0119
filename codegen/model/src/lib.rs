//! The seam between generated and hand-written code: the traits every twv model implements.
//!
//! Conventions (shared by generated code, the IR interpreter and all analysis code):
//! - Sizes are const generics: `NX` states, `NU` inputs. Parameters live inside the model value
//!   (runtime struct) or are folded as constants (baked build); they are not an argument.
//! - Vectors are `[f64; N]`. Dense matrices are row-major arrays of rows:
//!   `jac[i][j] = ∂f_i/∂x_j`. The sparse Jacobian is in compressed-column (CCS) order, the order
//!   CasADi and the IR use: `jac_x_colind()` has `NX + 1` entries, `jac_x_row()` the row of each
//!   stored value.
//! - Tangent vectors for the variational equations are `[[f64; NX]; K]`: `w[k]` is the k-th
//!   vector and `jw` writes `out[k] = (∂f/∂x) w[k]`.
//! - No method allocates or panics for finite or non-finite inputs; non-finite inputs give
//!   non-finite outputs.
#![no_std]

mod padded;

pub use padded::{NoModel, Padded};

/// Points one lanes kernel evaluates at once ([`Model::f_jw_jac_u_lanes`]); the arithmetic
/// behind it is `twv_kernels::lanes`.
pub const LANES: usize = 8;

/// Names and descriptive metadata of a model.
#[derive(Debug, Clone, Copy)]
pub struct ModelInfo {
    /// Model name (the CLI's `--model` value).
    pub name: &'static str,
    /// Content hash of the IR the code came from (`sha256:...`), or "" for hand-written models.
    pub ir_hash: &'static str,
    /// State names, in state order.
    pub states: &'static [&'static str],
    /// Input names, in input order.
    pub inputs: &'static [&'static str],
    /// Parameter names, in parameter order.
    pub params: &'static [&'static str],
}

/// Metadata of one scalar parameter, as declared in the model IR (`params`), so that code
/// holding only a generated model can still say what each entry of its parameter vector means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamInfo {
    /// Parameter name (`I2_xx`).
    pub name: &'static str,
    /// TOML key its value is read from (`I2`).
    pub key: &'static str,
    /// Component of the TOML array, or `None` for a scalar key.
    pub index: Option<usize>,
    /// SI unit.
    pub unit: &'static str,
    /// Validation kind: `mass`, `inertia`, `gravity`, `length` or `other`.
    pub kind: &'static str,
    /// Value used for the IR's golden values.
    pub default: f64,
    /// False when the model's equations do not contain the parameter.
    pub used: bool,
    /// One line of description.
    pub description: &'static str,
}

/// A model ẋ = f(x, u) with its Jacobians.
pub trait Model<const NX: usize, const NU: usize> {
    /// Whether the model's functions are Rust compiled into the program (generated or
    /// written by hand), a few nanoseconds a call: then the code around them (the integrators'
    /// steps) is worth building once per instruction set. False for a model that only
    /// evaluates an IR at run time (the interpreter, or its native code), whose calls cost
    /// microseconds: those builds would only cost compile time.
    const COMPILED_IN: bool = true;

    /// Names of the model, its states, inputs and parameters.
    fn info(&self) -> ModelInfo;

    /// ẋ = f(x, u).
    fn f(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NX]);

    /// Dense ∂f/∂x, row-major.
    fn jac_x(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [[f64; NX]; NX]);

    /// Dense ∂f/∂u, row-major (`out[i][j] = ∂f_i/∂u_j`).
    fn jac_u(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [[f64; NU]; NX]);

    /// Column pointers of the structural non-zeros of ∂f/∂x (CCS, `NX + 1` entries).
    fn jac_x_colind(&self) -> &[usize];

    /// Row of each structural non-zero of ∂f/∂x (CCS order).
    fn jac_x_row(&self) -> &[usize];

    /// The structural non-zeros of ∂f/∂x in CCS order; `values.len()` must equal
    /// `jac_x_row().len()` (shorter slices are filled as far as they go).
    fn jac_x_sparse(&self, x: &[f64; NX], u: &[f64; NU], values: &mut [f64]);

    /// ẋ and `out[k] = (∂f/∂x) w[k]` together: the hot kernel of the variational equations.
    fn f_jw<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    );

    /// [`f_jw`](Self::f_jw) that also returns tr(∂f/∂x), for the Σλ = ⟨tr J⟩ check of the
    /// Lyapunov code. The default evaluates the dense Jacobian a second time; generated code
    /// overrides it with the sum of the diagonal entries it has already computed.
    fn f_jw_trace<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) -> f64 {
        self.f_jw(x, u, w, f, out);
        let mut jac = [[0.0; NX]; NX];
        self.jac_x(x, u, &mut jac);
        (0..NX).map(|i| jac[i][i]).sum()
    }

    /// [`f_jw`](Self::f_jw) and the dense ∂f/∂u at the same point: what a closed loop needs
    /// at every stage (its Jacobian is f_x + f_u u_x). The default calls both; generated code
    /// evaluates them in one kernel, so their common subexpressions (the factorisation of the
    /// mass matrix) are computed once, with bit-identical results.
    fn f_jw_jac_u<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
        jac_u: &mut [[f64; NU]; NX],
    ) {
        self.f_jw(x, u, w, f, out);
        self.jac_u(x, u, jac_u);
    }

    /// [`f_jw_jac_u`](Self::f_jw_jac_u) with one tangent vector at [`LANES`]
    /// independent points (`x[l]`, `u[l]`, `w[l]` → `f[l]`, `out[l]`, `jac_u[l]`), for maps over
    /// many points. Every lane gets exactly the bits of the one-point call; the default makes
    /// those calls, generated code evaluates all lanes in one instruction stream.
    fn f_jw_jac_u_lanes(
        &self,
        x: &[[f64; NX]; LANES],
        u: &[[f64; NU]; LANES],
        w: &[[f64; NX]; LANES],
        f: &mut [[f64; NX]; LANES],
        out: &mut [[f64; NX]; LANES],
        jac_u: &mut [[[f64; NU]; NX]; LANES],
    ) {
        for l in 0..LANES {
            self.f_jw_jac_u::<1>(
                &x[l],
                &u[l],
                core::array::from_ref(&w[l]),
                &mut f[l],
                core::array::from_mut(&mut out[l]),
                &mut jac_u[l],
            );
        }
    }

    /// [`f_jw_jac_u_lane_arrays`](Self::f_jw_jac_u_lane_arrays) given the lane (sin, cos) of
    /// state `given.0`, as `twv_kernels::lanes::sin_cos` computes it (the bits the kernel's own
    /// would have): a caller that needs it too (the maps' sine setpoint needs the pitch's)
    /// computes it once for both. The default ignores it, as does a kernel that takes no sine
    /// of that state.
    #[allow(clippy::too_many_arguments)]
    fn f_jw_jac_u_lane_arrays_given(
        &self,
        x: &[[f64; LANES]; NX],
        u: &[[f64; LANES]; NU],
        w: &[[f64; LANES]; NX],
        f: &mut [[f64; LANES]; NX],
        out: &mut [[f64; LANES]; NX],
        jac_u: &mut [[[f64; LANES]; NU]; NX],
        given: (usize, &([f64; LANES], [f64; LANES])),
    ) {
        let _ = given;
        self.f_jw_jac_u_lane_arrays(x, u, w, f, out, jac_u);
    }

    /// [`f_jw_jac_u_lanes`](Self::f_jw_jac_u_lanes) on lane arrays: entry `i` of point `l` is
    /// `x[i][l]` (and so for every argument), the form a caller that keeps its points that way
    /// passes without transposing. The default transposes around `f_jw_jac_u_lanes`; generated
    /// code runs its lanes kernel on the arrays directly. The bits of the one-point call.
    fn f_jw_jac_u_lane_arrays(
        &self,
        x: &[[f64; LANES]; NX],
        u: &[[f64; LANES]; NU],
        w: &[[f64; LANES]; NX],
        f: &mut [[f64; LANES]; NX],
        out: &mut [[f64; LANES]; NX],
        jac_u: &mut [[[f64; LANES]; NU]; NX],
    ) {
        let point = |l: usize| -> ([f64; NX], [f64; NU], [f64; NX]) {
            (
                core::array::from_fn(|i| x[i][l]),
                core::array::from_fn(|k| u[k][l]),
                core::array::from_fn(|i| w[i][l]),
            )
        };
        let (mut xl, mut ul, mut wl) = ([[0.0; NX]; LANES], [[0.0; NU]; LANES], [[0.0; NX]; LANES]);
        for l in 0..LANES {
            (xl[l], ul[l], wl[l]) = point(l);
        }
        let (mut fl, mut ol, mut jl) = (
            [[0.0; NX]; LANES],
            [[0.0; NX]; LANES],
            [[[0.0; NU]; NX]; LANES],
        );
        self.f_jw_jac_u_lanes(&xl, &ul, &wl, &mut fl, &mut ol, &mut jl);
        for l in 0..LANES {
            for i in 0..NX {
                (f[i][l], out[i][l]) = (fl[l][i], ol[l][i]);
                for k in 0..NU {
                    jac_u[i][k][l] = jl[l][i][k];
                }
            }
        }
    }

    /// `out[k] = (∂f/∂x) w[k]` without ẋ.
    fn jw<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        out: &mut [[f64; NX]; K],
    ) {
        let mut f = [0.0; NX];
        self.f_jw(x, u, w, &mut f, out);
    }
}

/// Generic work over a model whose type is only chosen at run time (a `--model NAME` or an
/// `--ir FILE`): the dispatcher (`twv_generated::visit`, `twv_ir::visit_interpreted`) calls
/// `visit` with the concrete model, so the work is monomorphised as if the caller had named it.
pub trait ModelVisitor {
    /// What the visit returns.
    type Output;
    /// Do the work with a concrete model.
    fn visit<const NX: usize, const NU: usize, M: Model<NX, NU>>(self, model: M) -> Self::Output;
}

/// The parts of a mechanical model in Poincaré form M(q) ṗ + C(q,p) p + F(q) = Q(u), used by
/// the audit and the invariant checks. `NS` is the number of quasi-velocities (the last `NS`
/// states). Matrices are row-major.
pub trait Mechanical<const NX: usize, const NU: usize, const NS: usize>: Model<NX, NU> {
    /// Mass matrix M(q).
    fn mass_matrix(&self, x: &[f64; NX], out: &mut [[f64; NS]; NS]);
    /// Velocity terms C(q,p) p.
    fn cp(&self, x: &[f64; NX], out: &mut [f64; NS]);
    /// Gravity terms F(q).
    fn gravity(&self, x: &[f64; NX], out: &mut [f64; NS]);
    /// Generalized input forces Q(u) (may depend on q).
    fn input_forces(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NS]);
    /// Total energy T + V.
    fn energy(&self, x: &[f64; NX]) -> f64;
    /// Planar linear momentum (X, Y) and angular momentum about the inertial origin (Z).
    fn momentum(&self, x: &[f64; NX]) -> [f64; 3];
}
