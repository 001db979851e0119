//! `vehicle7`: the rolling vehicle, no side slip (v_y ≡ 0), a nonholonomic constraint.
//!
//! State (Φ, x, y, θ, w_y, v_x, w_z), inputs (F1, T2). The equations are the v_y-free rows of
//! the *unconstrained* vehicle8 equations (Kane / Lagrange–d'Alembert projection, DERIVATION.md
//! §5), evaluated at v_y = 0; written out here on their own:
//!
//! ```text
//! M  = [ I_p     m2 b c  0       ]     F = (−m2 g b s, 0, 0)
//!      [ m2 b c  M_t     0       ]     Q = (0, F1, T2)
//!      [ 0       0       I_zz(Φ) ]
//! Cp = ( −K s c w_z²,
//!        −m2 b s w_y² − m2 b s w_z²,
//!        2 K s c w_y w_z + m2 b s v_x w_z )
//! ```
//!
//! The last terms of rows 2 and 3 are the gyroscopic pair that substituting v_y = 0 into the
//! Lagrangian would lose ([`Mistake::DropGyroscopicPair`]).

use super::scalar::Real;
use super::{a_to_n, planar_velocity, HandEquations, Mistake, VehicleParams, STATES7};
use twv_model::ModelInfo;

/// Hand model of `vehicle7` (see the module documentation for its equations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandVehicle7 {
    params: VehicleParams,
    mistake: Option<Mistake>,
}

impl HandVehicle7 {
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

impl HandEquations<7, 2, 3> for HandVehicle7 {
    fn model_info(&self) -> ModelInfo {
        ModelInfo {
            name: "vehicle7",
            ir_hash: "",
            states: &STATES7,
            inputs: &["F1", "T2"],
            params: &super::PARAM_NAMES,
        }
    }

    fn mass<S: Real>(&self, x: &[S; 7]) -> [[S; 3]; 3] {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let mb = p.m2 * p.b;
        let mt = S::cst(p.m1 + p.m2);
        let ip = S::cst(p.i2[1] + p.m2 * p.b * p.b);
        let izz = s * s * (p.i2[0] + p.m2 * p.b * p.b) + c * c * p.i2[2] + p.i1[2];
        let z = S::cst(0.0);
        [[ip, c * mb, z], [c * mb, mt, z], [z, z, izz]]
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
        [S::cst(0.0), u[0], u[1]]
    }

    fn qdot<S: Real>(&self, x: &[S; 7]) -> [S; 4] {
        let (xd, yd) = planar_velocity(x[3], x[5], S::cst(0.0));
        [x[4], xd, yd, x[6]]
    }

    fn energy_of<S: Real>(&self, x: &[S; 7]) -> S {
        let p = &self.params;
        let (s, c) = (x[0].sin(), x[0].cos());
        let (wy, vx, wz) = (x[4], x[5], x[6]);
        let t_base = vx * vx * (0.5 * p.m1) + wz * wz * (0.5 * p.i1[2]);
        let (vpx, vpy, vpz) = (vx + c * wy * p.b, s * wz * p.b, -(s * wy * p.b));
        let (ox, oy, oz) = (-(s * wz), wy, c * wz);
        let t_pend = (vpx * vpx + vpy * vpy + vpz * vpz) * (0.5 * p.m2)
            + ox * ox * (0.5 * p.i2[0])
            + oy * oy * (0.5 * p.i2[1])
            + oz * oz * (0.5 * p.i2[2]);
        let v = c * (p.g * p.m2 * p.b) + p.g * p.m1 * p.a;
        t_base + t_pend + v
    }

    fn momentum_of(&self, x: &[f64; 7]) -> [f64; 3] {
        let p = &self.params;
        let (s, c) = x[0].sin_cos();
        let (px, py, th) = (x[1], x[2], x[3]);
        let (wy, vx, wz) = (x[4], x[5], x[6]);
        let v1 = a_to_n(th, vx, 0.0);
        let off2 = a_to_n(th, p.b * s, 0.0);
        let r2 = [px + off2[0], py + off2[1]];
        let v2 = a_to_n(th, vx + p.b * c * wy, p.b * s * wz);
        let spin = (p.i1[2] + p.i2[0] * s * s + p.i2[2] * c * c) * wz;
        [
            p.m1 * v1[0] + p.m2 * v2[0],
            p.m1 * v1[1] + p.m2 * v2[1],
            p.m1 * (px * v1[1] - py * v1[0]) + p.m2 * (r2[0] * v2[1] - r2[1] * v2[0]) + spin,
        ]
    }
}
