//! A model under a static state-feedback law u = k(t, x): the closed-loop vector field.

use twv_model::Model;

use super::open_loop::diag_sum;
use super::VectorField;

/// A static feedback law u = k(t, x) with its state Jacobian ∂k/∂x.
///
/// "Static" means the law has no states of its own; a PID with an integral state augments the
/// system instead (see [`field`](super::field)). Non-smooth laws (saturation) return the
/// derivative of the active branch.
pub trait FeedbackLaw<const NX: usize, const NU: usize> {
    /// The input u = k(t, x).
    fn input(&self, t: f64, x: &[f64; NX]) -> [f64; NU];

    /// ∂k/∂x at (t, x), row-major (`out[j][i] = ∂u_j/∂x_i`).
    fn jacobian(&self, t: f64, x: &[f64; NX], out: &mut [[f64; NX]; NU]);
}

/// ẋ = f(x, k(t, x)): a model closed by a static feedback law.
///
/// The tangent uses the exact closed-loop Jacobian J_cl = ∂f/∂x + ∂f/∂u ∂k/∂x: the model's
/// `f_jw_jac_u` gives (∂f/∂x) w and ∂f/∂u from one kernel, and each tangent vector gets
/// ∂f/∂u (∂k/∂x w) added, 2·NU·NX multiply-adds per vector (cheaper than forming J_cl when
/// NU < NX).
#[derive(Debug)]
pub struct ClosedLoop<'a, M, L, const NU: usize> {
    /// The model.
    pub model: &'a M,
    /// The feedback law.
    pub law: L,
}

// By hand: a derive would require `M: Clone`, but only the reference is copied.
impl<M, L: Clone, const NU: usize> Clone for ClosedLoop<'_, M, L, NU> {
    fn clone(&self) -> Self {
        Self {
            model: self.model,
            law: self.law.clone(),
        }
    }
}
impl<M, L: Copy, const NU: usize> Copy for ClosedLoop<'_, M, L, NU> {}

impl<'a, M, L, const NU: usize> ClosedLoop<'a, M, L, NU> {
    /// The model `model` closed by `law`.
    pub fn new(model: &'a M, law: L) -> Self {
        Self { model, law }
    }
}

/// ∂f/∂u and ∂k/∂x at (t, x, u).
#[inline(always)]
fn input_jacobians<M, L, const NX: usize, const NU: usize>(
    model: &M,
    law: &L,
    t: f64,
    x: &[f64; NX],
    u: &[f64; NU],
) -> JacPair<NX, NU>
where
    M: Model<NX, NU>,
    L: FeedbackLaw<NX, NU>,
{
    let mut b = [[0.0; NU]; NX];
    let mut kx = [[0.0; NX]; NU];
    model.jac_u(x, u, &mut b);
    law.jacobian(t, x, &mut kx);
    JacPair { b, kx }
}

/// ∂f/∂u (NX × NU) and ∂k/∂x (NU × NX).
struct JacPair<const NX: usize, const NU: usize> {
    b: [[f64; NU]; NX],
    kx: [[f64; NX]; NU],
}

impl<M, L, const NX: usize, const NU: usize> VectorField<NX> for ClosedLoop<'_, M, L, NU>
where
    M: Model<NX, NU>,
    L: FeedbackLaw<NX, NU>,
{
    const COMPILED_IN: bool = M::COMPILED_IN;

    #[inline(always)]
    fn eval<const K: usize>(
        &self,
        t: f64,
        x: &[f64; NX],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        jw: &mut [[f64; NX]; K],
    ) {
        let u = self.law.input(t, x);
        if K == 0 {
            self.model.f_jw(x, &u, w, f, jw);
            return;
        }
        // ∂f/∂u from the same kernel as ∂f/∂x (their common subexpressions computed once).
        let mut b = [[0.0; NU]; NX];
        self.model.f_jw_jac_u(x, &u, w, f, jw, &mut b);
        let mut kx = [[0.0; NX]; NU];
        self.law.jacobian(t, x, &mut kx);
        for (wk, out) in w.iter().zip(jw.iter_mut()) {
            // du = (∂k/∂x) w_k, then out += (∂f/∂u) du.
            let du: [f64; NU] = core::array::from_fn(|j| dot(&kx[j], wk));
            for (o, brow) in out.iter_mut().zip(b.iter()) {
                *o += dot(brow, &du);
            }
        }
    }

    #[inline(always)]
    fn rhs(&self, t: f64, x: &[f64; NX], f: &mut [f64; NX]) {
        let u = self.law.input(t, x);
        self.model.f(x, &u, f);
    }

    /// tr J_cl = tr ∂f/∂x + Σ_ij (∂f/∂u)_ij (∂k/∂x)_ji.
    #[inline]
    fn trace_jacobian(&self, t: f64, x: &[f64; NX]) -> f64 {
        let u = self.law.input(t, x);
        let mut j = [[0.0; NX]; NX];
        self.model.jac_x(x, &u, &mut j);
        let JacPair { b, kx } = input_jacobians(self.model, &self.law, t, x, &u);
        let mut tr = diag_sum(&j);
        for (i, brow) in b.iter().enumerate() {
            for (bij, kxj) in brow.iter().zip(kx.iter()) {
                tr += bij * kxj[i];
            }
        }
        tr
    }

    fn jacobian(&self, t: f64, x: &[f64; NX], out: &mut [[f64; NX]; NX]) {
        let u = self.law.input(t, x);
        self.model.jac_x(x, &u, out);
        let JacPair { b, kx } = input_jacobians(self.model, &self.law, t, x, &u);
        for (orow, brow) in out.iter_mut().zip(b.iter()) {
            for (j, o) in orow.iter_mut().enumerate() {
                *o += brow
                    .iter()
                    .zip(kx.iter())
                    .map(|(bk, kk)| bk * kk[j])
                    .sum::<f64>();
            }
        }
    }
}

/// a · b.
#[inline(always)]
pub(crate) fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b.iter()) {
        s += x * y;
    }
    s
}
