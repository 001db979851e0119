//! The planar cart–pendulum that every twv vehicle reduces to with T2 = 0 (docs/src/conventions.md), in
//! closed form: its linearisation at the upright and the Routh–Hurwitz conditions of the PID
//! pitch loop. Used as the reference the numerical analysis is checked against.
//!
//! Linearised: I_p Φ̈ + m_p l v̇_x = m_p g l Φ, m_p l Φ̈ + M_x v̇_x = F, with I_p = I_y + m_p l²
//! and Δ = I_p M_x − m_p² l². With F = Kp Φ + Ki ∫Φ + Kd Φ̇ the pitch loop's characteristic
//! polynomial is s³ + (m_p l Kd/Δ) s² + (m_p l (Kp − M_x g)/Δ) s + m_p l Ki/Δ, which is Hurwitz
//! iff Kd > 0, Kp > M_x g and 0 < Ki < m_p l Kd (Kp − M_x g)/Δ (for Ki = 0, PD, the first two).

use nalgebra::DMatrix;

use super::error::{check_finite, LinearError};
use super::pitch::PidGains;

/// Physical parameters of the cart–pendulum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartPendulum {
    /// Pendulum mass m_p (kg).
    pub m_p: f64,
    /// Hinge-to-centroid distance l (m).
    pub l: f64,
    /// Pendulum pitch inertia about its centroid I_y (kg m²).
    pub i_y: f64,
    /// Translating mass M_x (kg): base plus pendulum (plus rolling equivalents).
    pub m_x: f64,
    /// Gravity g (m/s²).
    pub g: f64,
}

impl CartPendulum {
    /// From the vehicle parameters of docs/src/conventions.md: base mass `m1`, pendulum mass `m2`, centroid
    /// distance `b`, pendulum inertia `i2_yy`, gravity `g` (M_x = m1 + m2).
    pub fn from_vehicle(m1: f64, m2: f64, b: f64, i2_yy: f64, g: f64) -> Result<Self, LinearError> {
        check_finite("cart-pendulum parameters", [m1, m2, b, i2_yy, g].iter())?;
        for (what, value) in [("m1", m1), ("m2", m2), ("b", b), ("I2_yy", i2_yy), ("g", g)] {
            if value <= 0.0 {
                return Err(LinearError::NonPositive { what, value });
            }
        }
        Ok(Self {
            m_p: m2,
            l: b,
            i_y: i2_yy,
            m_x: m1 + m2,
            g,
        })
    }

    /// I_p = I_y + m_p l², the pitch inertia about the hinge.
    pub fn i_p(&self) -> f64 {
        self.i_y + self.m_p * self.l * self.l
    }

    /// Δ = I_p M_x − m_p² l² (> 0: the determinant of the mass matrix).
    pub fn delta(&self) -> f64 {
        self.i_p() * self.m_x - (self.m_p * self.l).powi(2)
    }

    /// λ² = m_p g l M_x / Δ: the upright's eigenvalues are ±λ.
    pub fn lambda_sq(&self) -> f64 {
        self.m_p * self.g * self.l * self.m_x / self.delta()
    }

    /// A (4 × 4) and B (4 × 1) at the upright, states [`Self::state_names`], input F.
    pub fn matrices(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        let d = self.delta();
        let ml = self.m_p * self.l;
        let mut a = DMatrix::zeros(4, 4);
        a[(0, 2)] = 1.0;
        a[(1, 3)] = 1.0;
        a[(2, 0)] = self.m_x * ml * self.g / d;
        a[(3, 0)] = -ml * ml * self.g / d;
        let b = DMatrix::from_column_slice(4, 1, &[0.0, 0.0, -ml / d, self.i_p() / d]);
        (a, b)
    }

    /// State names of [`Self::matrices`]: (Φ, x, w_y, v_x).
    pub fn state_names() -> Vec<String> {
        ["phi", "x", "w_y", "v_x"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Upper limit of Ki: m_p l Kd (Kp − M_x g) / Δ.
    pub fn ki_limit(&self, kp: f64, kd: f64) -> f64 {
        self.m_p * self.l * kd * (kp - self.m_x * self.g) / self.delta()
    }

    /// The Routh–Hurwitz verdict on the pitch loop (PD when Ki = 0).
    pub fn routh_hurwitz_stable(&self, g: &PidGains) -> bool {
        let pd = g.kd > 0.0 && g.kp > self.m_x * self.g;
        if g.ki == 0.0 {
            pd
        } else {
            pd && g.ki > 0.0 && g.ki < self.ki_limit(g.kp, g.kd)
        }
    }
}
