//! The vector field seam: what the integrators integrate.
//!
//! A [`VectorField<N>`] is an autonomous or time-dependent system ẋ = F(t, x) on `N` states that
//! can also apply its Jacobian J = ∂F/∂x to tangent vectors. The integrators and the Lyapunov
//! code only ever see this trait, so an open-loop model, a model under feedback, or a model plus
//! a controller with its own states are all integrated by the same code.
//!
//! # Dynamic controllers (PID): augment the state
//!
//! A controller with internal states z (an integrator, a derivative filter) turns the model into
//! the augmented system on `NA = NX + NZ` states
//!
//! ```text
//! ẋ = f(x, u),  ż = g(x, z),  u = k(x, z)
//! J_aug = [ f_x + f_u k_x   f_u k_z ]
//!         [ g_x             g_z     ]
//! ```
//!
//! Implement `VectorField<NA>` for a type holding `&M` and the controller, with
//! `const { assert!(NA == NX + NZ) }` inside `eval` (stable Rust cannot write `NX + NZ` as a
//! const argument, so the sum is a parameter checked at compile time). In `eval`, split `x_aug`
//! and every tangent vector into the `x` and `z` parts, call `model.f_jw` on the `x` parts with
//! `u = k(x, z)`, then add `f_u (k_x w_x + k_z w_z)` to the `x` rows (one `jac_u` per stage) and
//! write `g_x w_x + g_z w_z` into the `z` rows. Saturation makes `k` non-smooth; use the
//! derivative of the active branch (zero when saturated), which is the almost-everywhere
//! Jacobian the Lyapunov exponents need. [`ClosedLoop`](super::ClosedLoop) is the `NZ = 0` case
//! and shows the pattern.

/// A vector field ẋ = F(t, x) with its Jacobian–vector products: the thing being integrated.
///
/// Implementations must not allocate or panic; non-finite inputs give non-finite outputs (the
/// integrators detect and report them).
pub trait VectorField<const N: usize> {
    /// Whether the field's model is compiled into the program ([`Model::COMPILED_IN`]): then
    /// the integrators' steps run from a build for each instruction set, chosen by timing
    /// ([`twv_kernels::isa::Calibration`]). A field that evaluates an IR at run time says
    /// false, and the steps are built once: its calls cost microseconds, the combinations of
    /// a step nanoseconds.
    ///
    /// [`Model::COMPILED_IN`]: twv_model::Model::COMPILED_IN
    const COMPILED_IN: bool = true;

    /// ẋ = F(t, x) into `f` and `jw[k] = J(t, x) w[k]` for each of the `K` tangent vectors: the
    /// hot kernel, one call per integrator stage.
    fn eval<const K: usize>(
        &self,
        t: f64,
        x: &[f64; N],
        w: &[[f64; N]; K],
        f: &mut [f64; N],
        jw: &mut [[f64; N]; K],
    );

    /// [`eval`](Self::eval) that also returns tr J(t, x), for the ∫ tr J quadrature. The
    /// default adds [`trace_jacobian`](Self::trace_jacobian); fields whose model computes the
    /// Jacobian anyway (generated code) override it to get the trace for free.
    #[inline]
    fn eval_trace<const K: usize>(
        &self,
        t: f64,
        x: &[f64; N],
        w: &[[f64; N]; K],
        f: &mut [f64; N],
        jw: &mut [[f64; N]; K],
    ) -> f64 {
        self.eval(t, x, w, f, jw);
        self.trace_jacobian(t, x)
    }

    /// ẋ = F(t, x) alone.
    #[inline]
    fn rhs(&self, t: f64, x: &[f64; N], f: &mut [f64; N]) {
        self.eval::<0>(t, x, &[], f, &mut []);
    }

    /// The trace of J(t, x). The default applies [`eval`](Self::eval) to the unit vectors
    /// (N directional derivatives); implementors with a cheaper diagonal should override it,
    /// because the Lyapunov code integrates it at every stage for the Σλ = ⟨tr J⟩ check.
    fn trace_jacobian(&self, t: f64, x: &[f64; N]) -> f64 {
        let mut j = [[0.0; N]; N];
        self.jacobian(t, x, &mut j);
        (0..N).map(|i| j[i][i]).sum()
    }

    /// The dense Jacobian J(t, x), row-major (`out[i][j] = ∂F_i/∂x_j`): used for linearisation
    /// and eigenvalues, not in the hot loop. The default applies [`eval`](Self::eval) to the
    /// unit vectors.
    fn jacobian(&self, t: f64, x: &[f64; N], out: &mut [[f64; N]; N]) {
        let mut e = [[0.0; N]; N];
        for (i, row) in e.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        let mut f = [0.0; N];
        let mut cols = [[0.0; N]; N];
        self.eval::<N>(t, x, &e, &mut f, &mut cols);
        for (j, col) in cols.iter().enumerate() {
            for (i, v) in col.iter().enumerate() {
                out[i][j] = *v;
            }
        }
    }
}

/// A borrowed field is a field, so a stepper can own `&F` while the caller keeps `F`.
impl<const N: usize, F: VectorField<N> + ?Sized> VectorField<N> for &F {
    const COMPILED_IN: bool = F::COMPILED_IN;

    #[inline(always)]
    fn eval<const K: usize>(
        &self,
        t: f64,
        x: &[f64; N],
        w: &[[f64; N]; K],
        f: &mut [f64; N],
        jw: &mut [[f64; N]; K],
    ) {
        (**self).eval(t, x, w, f, jw);
    }

    #[inline(always)]
    fn eval_trace<const K: usize>(
        &self,
        t: f64,
        x: &[f64; N],
        w: &[[f64; N]; K],
        f: &mut [f64; N],
        jw: &mut [[f64; N]; K],
    ) -> f64 {
        (**self).eval_trace(t, x, w, f, jw)
    }

    #[inline(always)]
    fn rhs(&self, t: f64, x: &[f64; N], f: &mut [f64; N]) {
        (**self).rhs(t, x, f);
    }

    #[inline(always)]
    fn trace_jacobian(&self, t: f64, x: &[f64; N]) -> f64 {
        (**self).trace_jacobian(t, x)
    }

    fn jacobian(&self, t: f64, x: &[f64; N], out: &mut [[f64; N]; N]) {
        (**self).jacobian(t, x, out);
    }
}
