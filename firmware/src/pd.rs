//! The pitch loop of `twv simulate` with its defaults' structure (PD on the measured rate, a
//! sine or zero setpoint, optional saturation; no integral, rate filter, velocity or yaw loop),
//! written with the analysis library's operations in its order (`control::field`), so that the
//! closed loop here has the library's bits.

use twv_kernels::trig::sin_cos;
use twv_model::{Model, ModelInfo};

/// The law F = sat(Kp (Φ − A sin Φ) + Kd w_y), the force driving input `F1`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PitchPd {
    /// Kp [N/rad].
    pub kp: f64,
    /// Kd [N s/rad].
    pub kd: f64,
    /// A of the setpoint Φ_ref = A sin Φ [rad]; 0 for an upright setpoint.
    pub setpoint_amplitude: f64,
    /// The force limit |F| ≤ f_max [N]; infinity for none.
    pub f_max: f64,
}

impl PitchPd {
    /// The applied force at pitch `phi` [rad] and pitch rate `w_y` [rad/s].
    #[inline]
    pub fn force(&self, phi: f64, w_y: f64) -> f64 {
        let (s, _) = sin_cos(phi);
        let e = phi - self.setpoint_amplitude * s;
        let command = self.kp * e + self.kd * w_y;
        if command > self.f_max {
            self.f_max
        } else if command < -self.f_max {
            -self.f_max
        } else {
            command
        }
    }
}

/// Where the law reads and acts in a model: the states `phi`, `w_y` and the input `F1` (and
/// `T2`, held at zero), found by name as the library's controller finds them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wiring<const NU: usize> {
    phi: usize,
    w_y: usize,
    force: [f64; NU],
    yaw: [f64; NU],
}

impl<const NU: usize> Wiring<NU> {
    /// The wiring of a model, or `None` when it lacks `phi`, `w_y` or `F1`.
    pub fn of(info: &ModelInfo) -> Option<Self> {
        let find = |names: &[&str], name: &str| names.iter().position(|n| *n == name);
        let unit =
            |i: Option<usize>| core::array::from_fn(|j| if Some(j) == i { 1.0 } else { 0.0 });
        Some(Self {
            phi: find(info.states, "phi")?,
            w_y: find(info.states, "w_y")?,
            force: unit(Some(find(info.inputs, "F1")?)),
            yaw: unit(find(info.inputs, "T2")),
        })
    }

    /// The model input for force `f` (the library's u = F·force + T·yaw with T = 0: the same
    /// operations, so a −0 force gives the library's +0).
    #[inline]
    pub fn input(&self, f: f64) -> [f64; NU] {
        core::array::from_fn(|j| self.force[j] * f + self.yaw[j] * 0.0)
    }
}

/// A model closed by a [`PitchPd`]: ẋ = f(x, u(x)).
#[derive(Debug, Clone, Copy)]
pub struct ClosedLoop<'a, M, const NX: usize, const NU: usize> {
    model: &'a M,
    law: PitchPd,
    wiring: Wiring<NU>,
}

impl<'a, M: Model<NX, NU>, const NX: usize, const NU: usize> ClosedLoop<'a, M, NX, NU> {
    /// `model` closed by `law`, or `None` when the model lacks the law's states or input.
    pub fn new(model: &'a M, law: PitchPd) -> Option<Self> {
        Some(Self {
            model,
            law,
            wiring: Wiring::of(&model.info())?,
        })
    }

    /// The force the law applies at `x` [N].
    #[inline]
    pub fn force(&self, x: &[f64; NX]) -> f64 {
        let w = &self.wiring;
        let at = |i: usize| x.get(i).copied().unwrap_or(f64::NAN);
        self.law.force(at(w.phi), at(w.w_y))
    }

    /// The input the law applies at `x`.
    #[inline]
    pub fn input(&self, x: &[f64; NX]) -> [f64; NU] {
        self.wiring.input(self.force(x))
    }

    /// ẋ of the closed loop.
    #[inline]
    pub fn f(&self, x: &[f64; NX], out: &mut [f64; NX]) {
        self.model.f(x, &self.input(x), out);
    }

    /// `steps` RK4 steps of size `h` from `x`, in place; `false` (and `x` non-finite) when the
    /// state blew up, where the run stops.
    pub fn rk4(&self, x: &mut [f64; NX], h: f64, steps: u32) -> bool {
        let f = |x: &[f64], out: &mut [f64]| match (
            <&[f64; NX]>::try_from(x),
            <&mut [f64; NX]>::try_from(&mut *out),
        ) {
            (Ok(x), Ok(out)) => self.f(x, out),
            _ => out.fill(f64::NAN),
        };
        for _ in 0..steps {
            if !twv_step::rk4_step_array(f, x, h) {
                return false;
            }
        }
        true
    }
}
