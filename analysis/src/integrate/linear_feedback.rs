//! The static linear state feedback u = u0 − K (x − x_ref).

use super::FeedbackLaw;

/// u = u0 − K (x − x_ref): LQR, pole placement, or a PD law on measured states written as a
/// gain row. Its Jacobian is the constant −K, so [`ClosedLoop`](super::ClosedLoop) integrates
/// the exact closed-loop tangent (A − B K at an equilibrium).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearStateFeedback<const NX: usize, const NU: usize> {
    /// Feed-forward input u0 (e.g. the equilibrium input).
    pub u0: [f64; NU],
    /// Reference state x_ref.
    pub x_ref: [f64; NX],
    /// Gain K, row-major (`gain[j][i]` multiplies x_i − x_ref_i in u_j).
    pub gain: [[f64; NX]; NU],
}

impl<const NX: usize, const NU: usize> LinearStateFeedback<NX, NU> {
    /// u = −K x (regulation to the origin with zero feed-forward).
    pub fn regulator(gain: [[f64; NX]; NU]) -> Self {
        Self {
            u0: [0.0; NU],
            x_ref: [0.0; NX],
            gain,
        }
    }
}

impl<const NX: usize, const NU: usize> FeedbackLaw<NX, NU> for LinearStateFeedback<NX, NU> {
    #[inline(always)]
    fn input(&self, _t: f64, x: &[f64; NX]) -> [f64; NU] {
        core::array::from_fn(|j| {
            let mut u = self.u0[j];
            for ((k, xi), ri) in self.gain[j].iter().zip(x.iter()).zip(self.x_ref.iter()) {
                u -= k * (xi - ri);
            }
            u
        })
    }

    #[inline(always)]
    fn jacobian(&self, _t: f64, _x: &[f64; NX], out: &mut [[f64; NX]; NU]) {
        for (o, k) in out.iter_mut().zip(self.gain.iter()) {
            for (oi, ki) in o.iter_mut().zip(k.iter()) {
                *oi = -ki;
            }
        }
    }
}
