//! `vehicle8`: the study's model, hinge point free to move in the plane (no side-slip constraint).
//!
//! State (Φ, x, y, θ, w_y, v_x, v_y, w_z), inputs (F1, T2). With s = sinΦ, c = cosΦ,
//! M_t = m1 + m2, I_p = I2_yy + m2 b², K = I2_xx − I2_zz + m2 b² and
//! I_zz(Φ) = I1_zz + (I2_xx + m2 b²) s² + I2_zz c² (DERIVATION.md §3–4):
//!
//! ```text
//! M  = [ I_p     m2 b c  0       0       ]     F = (−m2 g b s, 0, 0, 0)
//!      [ m2 b c  M_t     0       0       ]     Q = (0, F1, 0, T2)
//!      [ 0       0       M_t     m2 b s  ]
//!      [ 0       0       m2 b s  I_zz(Φ) ]
//! Cp = ( −m2 b c v_y w_z − K s c w_z²,
//!        −m2 b s w_y² − M_t v_y w_z − m2 b s w_z²,
//!        2 m2 b c w_y w_z + M_t v_x w_z,
//!        2 K s c w_y w_z + m2 b s v_x w_z )
//! ```

use super::scalar::Real;
use super::{a_to_n, planar_velocity, HandEquations, Mistake, VehicleParams, STATES8};
use twv_model::ModelInfo;

/// Hand model of `vehicle8` (see the module documentation for its equations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandVehicle8 {
    params: VehicleParams,
    mistake: Option<Mistake>,
}

impl HandVehicle8 {
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

impl HandEquations<8, 2, 4> for HandVehicle8 {
    fn model_info(&self) -> ModelInfo {
        ModelInfo {
            name: "vehicle8",
            ir_hash: "",
            states: &STATES8,
            inputs: &["F1", "T2"],
            params: &super::PARAM_NAMES,
        }
    }

    fn mass<S: Real>(&self, x: &[S; 8]) -> [[S; 4]; 4] {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let mb = p.m2 * p.b;
        let mt = S::cst(p.m1 + p.m2);
        let ip = S::cst(p.i2[1] + p.m2 * p.b * p.b);
        let izz = s * s * (p.i2[0] + p.m2 * p.b * p.b) + c * c * p.i2[2] + p.i1[2];
        let z = S::cst(0.0);
        [
            [ip, c * mb, z, z],
            [c * mb, mt, z, z],
            [z, z, mt, s * mb],
            [z, z, s * mb, izz],
        ]
    }

    fn velocity_terms<S: Real>(&self, x: &[S; 8]) -> [S; 4] {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let (wy, vx, vy, wz) = (x[4], x[5], x[6], x[7]);
        let mb = p.m2 * p.b;
        let mt = p.m1 + p.m2;
        let k = p.i2[0] - p.i2[2] + p.m2 * p.b * p.b;
        // The pair from the pendulum's lateral momentum m2 b s w_z (see Mistake).
        let pair = if self.mistake == Some(Mistake::DropGyroscopicPair) {
            0.0
        } else {
            1.0
        };
        [
            -(c * vy * wz * mb) - s * c * wz * wz * k,
            -(s * wy * wy * mb) - vy * wz * mt - s * wz * wz * (mb * pair),
            c * wy * wz * (2.0 * mb) + vx * wz * mt,
            s * c * wy * wz * (2.0 * k) + s * vx * wz * (mb * pair),
        ]
    }

    fn gravity_terms<S: Real>(&self, x: &[S; 8]) -> [S; 4] {
        let p = &self.params;
        let sign = if self.mistake == Some(Mistake::FlipGravitySign) {
            1.0
        } else {
            -1.0
        };
        let z = S::cst(0.0);
        [x[0].sin() * (sign * p.m2 * p.g * p.b), z, z, z]
    }

    fn input_terms<S: Real>(&self, _x: &[S; 8], u: &[S; 2]) -> [S; 4] {
        let z = S::cst(0.0);
        [z, u[0], z, u[1]]
    }

    fn qdot<S: Real>(&self, x: &[S; 8]) -> [S; 4] {
        let (xd, yd) = planar_velocity(x[3], x[5], x[6]);
        [x[4], xd, yd, x[7]]
    }

    fn energy_of<S: Real>(&self, x: &[S; 8]) -> S {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let (wy, vx, vy, wz) = (x[4], x[5], x[6], x[7]);
        // Base: centroid velocity = hinge velocity (a a_z is parallel to ω_A = w_z a_z).
        let t_base = (vx * vx + vy * vy) * (0.5 * p.m1) + wz * wz * (0.5 * p.i1[2]);
        // Pendulum centroid velocity in A and angular velocity in B.
        let (vpx, vpy, vpz) = (vx + c * wy * p.b, vy + s * wz * p.b, -(s * wy * p.b));
        let (ox, oy, oz) = (-(s * wz), wy, c * wz);
        let t_pend = (vpx * vpx + vpy * vpy + vpz * vpz) * (0.5 * p.m2)
            + ox * ox * (0.5 * p.i2[0])
            + oy * oy * (0.5 * p.i2[1])
            + oz * oz * (0.5 * p.i2[2]);
        let v = c * (p.g * p.m2 * p.b) + p.g * p.m1 * p.a;
        t_base + t_pend + v
    }

    fn momentum_of(&self, x: &[f64; 8]) -> [f64; 3] {
        let p = &self.params;
        let (s, c) = x[0].sin_cos();
        let (px, py, th) = (x[1], x[2], x[3]);
        let (wy, vx, vy, wz) = (x[4], x[5], x[6], x[7]);
        let v1 = a_to_n(th, vx, vy);
        let off2 = a_to_n(th, p.b * s, 0.0);
        let r2 = [px + off2[0], py + off2[1]];
        let v2 = a_to_n(th, vx + p.b * c * wy, vy + p.b * s * wz);
        let spin = (p.i1[2] + p.i2[0] * s * s + p.i2[2] * c * c) * wz;
        [
            p.m1 * v1[0] + p.m2 * v2[0],
            p.m1 * v1[1] + p.m2 * v2[1],
            p.m1 * (px * v1[1] - py * v1[0]) + p.m2 * (r2[0] * v2[1] - r2[1] * v2[0]) + spin,
        ]
    }
}
