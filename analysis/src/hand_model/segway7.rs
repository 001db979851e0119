//! `segway7`: the physical Segway: two rolling wheels (spin inertia included), pendulum = chassis
//! + rider hinged at the axle midpoint, motor torques between each wheel and the pendulum.
//!
//! State (Φ, x, y, θ, w_y, v_x, w_z), inputs (τ_L, τ_R). With M_x = m2 + 2 m_w + 2 J_a/R² and
//! I_zz(Φ) = (I2_xx + m2 b²) s² + I2_zz c² + 2 J_d + (m_w + J_a/R²) c_w²/2 (c_w the track width
//! `c`, s and c of Φ otherwise; DERIVATION.md §6):
//!
//! ```text
//! M  = [ I_p     m2 b c  0       ]     F = (−m2 g b s, 0, 0)
//!      [ m2 b c  M_x     0       ]     Q = (−(τ_L+τ_R), (τ_L+τ_R)/R, c_w (τ_R−τ_L)/(2R))
//!      [ 0       0       I_zz(Φ) ]
//! Cp = ( −K s c w_z²,
//!        −m2 b s w_y² − m2 b s w_z²,
//!        2 K s c w_y w_z + m2 b s v_x w_z )
//! ```
//!
//! The wheels add no velocity terms: they do not pitch, their centres move along a_x only, and
//! the gyroscopic moment of their spin (−J_a σ w_z a_x) is a roll moment the ground takes.

use super::scalar::Real;
use super::{a_to_n, planar_velocity, HandEquations, Mistake, VehicleParams, STATES7};
use twv_model::ModelInfo;

/// Hand model of `segway7` (see the module documentation for its equations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandSegway7 {
    params: VehicleParams,
    mistake: Option<Mistake>,
}

impl HandSegway7 {
    /// The correct model with these parameters.
    pub const fn new(params: VehicleParams) -> Self {
        Self {
            params,
            mistake: None,
        }
    }

    /// The same model with a deliberate derivation error (for the audit's own tests).
    pub const fn with_mistake(self, mistake: Mistake) -> Self {
        Self {
            params: self.params,
            mistake: Some(mistake),
        }
    }

    /// The parameters.
    pub const fn params(&self) -> &VehicleParams {
        &self.params
    }

    /// The deliberate mistake, if any.
    pub const fn mistake(&self) -> Option<Mistake> {
        self.mistake
    }
}

impl HandEquations<7, 2, 3> for HandSegway7 {
    fn model_info(&self) -> ModelInfo {
        ModelInfo {
            name: "segway7",
            ir_hash: "",
            states: &STATES7,
            inputs: &["tau_L", "tau_R"],
            params: &super::PARAM_NAMES,
        }
    }

    fn mass<S: Real>(&self, x: &[S; 7]) -> [[S; 3]; 3] {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let mb = p.m2 * p.b;
        let rolling = p.m_w + p.j_a / (p.r * p.r);
        let mx = S::cst(p.m2 + 2.0 * rolling);
        let ip = S::cst(p.i2[1] + p.m2 * p.b * p.b);
        let izz = s * s * (p.i2[0] + p.m2 * p.b * p.b)
            + c * c * p.i2[2]
            + (2.0 * p.j_d + 0.5 * rolling * p.c * p.c);
        let z = S::cst(0.0);
        [[ip, c * mb, z], [c * mb, mx, z], [z, z, izz]]
    }

    fn velocity_terms<S: Real>(&self, x: &[S; 7]) -> [S; 3] {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let (wy, vx, wz) = (x[4], x[5], x[6]);
        let mb = p.m2 * p.b;
        let k = p.i2[0] - p.i2[2] + p.m2 * p.b * p.b;
        let pair = if self.mistake == Some(Mistake::DropGyroscopicPair) {
            0.0
        } else {
            1.0
        };
        [
            -(s * c * wz * wz * k),
            -(s * wy * wy * mb) - s * wz * wz * (mb * pair),
            s * c * wy * wz * (2.0 * k) + s * vx * wz * (mb * pair),
        ]
    }

    fn gravity_terms<S: Real>(&self, x: &[S; 7]) -> [S; 3] {
        let p = &self.params;
        let sign = if self.mistake == Some(Mistake::FlipGravitySign) {
            1.0
        } else {
            -1.0
        };
        let z = S::cst(0.0);
        [x[0].sin() * (sign * p.m2 * p.g * p.b), z, z]
    }

    fn input_terms<S: Real>(&self, _x: &[S; 7], u: &[S; 2]) -> [S; 3] {
        let p = &self.params;
        let (tl, tr) = (u[0], u[1]);
        [
            -(tl + tr),
            (tl + tr) * (1.0 / p.r),
            (tr - tl) * (p.c / (2.0 * p.r)),
        ]
    }

    fn qdot<S: Real>(&self, x: &[S; 7]) -> [S; 4] {
        let (xd, yd) = planar_velocity(x[3], x[5], S::cst(0.0));
        [x[4], xd, yd, x[6]]
    }

    fn energy_of<S: Real>(&self, x: &[S; 7]) -> S {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let (wy, vx, wz) = (x[4], x[5], x[6]);
        let (vpx, vpy, vpz) = (vx + c * wy * p.b, s * wz * p.b, -(s * wy * p.b));
        let (ox, oy, oz) = (-(s * wz), wy, c * wz);
        let t_pend = (vpx * vpx + vpy * vpy + vpz * vpz) * (0.5 * p.m2)
            + ox * ox * (0.5 * p.i2[0])
            + oy * oy * (0.5 * p.i2[1])
            + oz * oz * (0.5 * p.i2[2]);
        // Wheel centres at ±(c/2) a_y: velocity (v_x ∓ (c/2) w_z) a_x; spin σ = that / R about
        // a_y; angular velocity w_z a_z + σ a_y (a_z ⊥ a_y, so J_d and J_a separate).
        let half = 0.5 * p.c;
        let vl = vx - wz * half;
        let vr = vx + wz * half;
        let (sl, sr) = (vl * (1.0 / p.r), vr * (1.0 / p.r));
        let t_wheels = (vl * vl + vr * vr) * (0.5 * p.m_w)
            + (sl * sl + sr * sr) * (0.5 * p.j_a)
            + wz * wz * p.j_d;
        let v = (c * p.b + p.r) * (p.g * p.m2) + 2.0 * p.g * p.m_w * p.r;
        t_pend + t_wheels + v
    }

    fn momentum_of(&self, x: &[f64; 7]) -> [f64; 3] {
        let p = &self.params;
        let (s, c) = x[0].sin_cos();
        let (px, py, th) = (x[1], x[2], x[3]);
        let (wy, vx, wz) = (x[4], x[5], x[6]);
        let half = 0.5 * p.c;
        let off2 = a_to_n(th, p.b * s, 0.0);
        let r2 = [px + off2[0], py + off2[1]];
        let v2 = a_to_n(th, vx + p.b * c * wy, p.b * s * wz);
        let offl = a_to_n(th, 0.0, half);
        let rl = [px + offl[0], py + offl[1]];
        let rr = [px - offl[0], py - offl[1]];
        let vl = a_to_n(th, vx - half * wz, 0.0);
        let vr = a_to_n(th, vx + half * wz, 0.0);
        let spin = (2.0 * p.j_d + p.i2[0] * s * s + p.i2[2] * c * c) * wz;
        let cross = |r: [f64; 2], v: [f64; 2]| r[0] * v[1] - r[1] * v[0];
        [
            p.m2 * v2[0] + p.m_w * (vl[0] + vr[0]),
            p.m2 * v2[1] + p.m_w * (vl[1] + vr[1]),
            p.m2 * cross(r2, v2) + p.m_w * (cross(rl, vl) + cross(rr, vr)) + spin,
        ]
    }
}
