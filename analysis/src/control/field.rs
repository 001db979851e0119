//! The closed loop as an augmented vector field on NA = NX + NZ states (model states, then the
//! controller's), with its exact Jacobian, so the same value runs in the integrators, the
//! simulations and `lyapunov_spectrum` (see [`crate::integrate::field`] for the recipe).

use twv_model::Model;

use super::error::ControlError;
use super::plant::Plant;
use super::settings::{AntiWindup, ControllerSettings, VelocityLoop};
use crate::integrate::VectorField;

mod lanes;
pub use lanes::LoopLanes;

/// Where each controller state sits in the augmented state (absolute indices ≥ NX), in the
/// order ∫e, rate filter, ∫(v_ref − v_x); absent states take no slot, so a PD law has NZ = 0
/// and its closed loop is exactly the model's size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layout {
    /// ∫(Φ − Φ_ref) dt [rad s].
    pub integral: Option<usize>,
    /// Filtered pitch rate [rad/s].
    pub filter: Option<usize>,
    /// ∫(v_ref − v_x) dt [m].
    pub velocity_integral: Option<usize>,
}

impl Layout {
    fn new(settings: &ControllerSettings, nx: usize) -> Self {
        let mut next = nx;
        let mut slot = |on: bool| {
            on.then(|| {
                next += 1;
                next - 1
            })
        };
        Self {
            integral: slot(settings.pitch.gains.ki != 0.0),
            filter: slot(settings.pitch.derivative_filter.is_some()),
            velocity_integral: slot(settings.velocity.as_ref().is_some_and(|v| v.ki != 0.0)),
        }
    }

    /// The controller states present, as (absolute index, name, unit).
    pub fn states(&self) -> Vec<(usize, &'static str, &'static str)> {
        [
            (self.integral, "int_e", "rad s"),
            (self.filter, "rate_f", "rad/s"),
            (self.velocity_integral, "int_ev", "m"),
        ]
        .into_iter()
        .filter_map(|(i, n, u)| i.map(|i| (i, n, u)))
        .collect()
    }
}

/// What the controller commands at one instant (for records and metrics).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command<const NU: usize> {
    /// Pitch setpoint Φ_ref including the velocity loop's lean [rad].
    pub phi_ref: f64,
    /// Unsaturated force command [N].
    pub force_cmd: f64,
    /// Applied (saturated) force F [N].
    pub force: f64,
    /// Yaw torque T [N m] (0 without a yaw loop).
    pub yaw: f64,
    /// Whether |F_cmd| > F_max.
    pub saturated: bool,
    /// The model input u = F·force + T·yaw.
    pub u: [f64; NU],
}

/// The law's values and, when asked, their gradients over the augmented state.
struct Law<const NA: usize, const NU: usize> {
    cmd: Command<NU>,
    /// ∂F/∂x_aug (zero while saturated: the active branch).
    d_force: [f64; NA],
    /// ∂T/∂x_aug.
    d_yaw: [f64; NA],
    /// ż of the three possible controller states (slot order of [`Layout`]) and their rows.
    zdot: [f64; 3],
    d_zdot: [[f64; NA]; 3],
}

/// The velocity loop's part of the law: its lean request and its integral's ż, with their rows.
struct Lean<const NA: usize> {
    lean: f64,
    d_lean: [f64; NA],
    zdot: f64,
    d_zdot: [f64; NA],
}

/// The law's derivative along one tangent vector w.
#[derive(Clone, Copy)]
struct Tangent<const NU: usize> {
    /// (∂u/∂x_aug) w.
    du: [f64; NU],
    /// (∂ż/∂x_aug) w per controller slot (0 where absent).
    dz: [f64; 3],
}

/// The model closed by the PID pitch loop (and optional velocity and yaw loops):
///
/// ```text
/// ẋ = f(x, u(t, x, z)),  ż = g(t, x, z),  u = F·force_dir + T·yaw_dir
/// J = [ f_x + f_u u_x   f_u u_z ]
///     [ g_x             g_z     ]
/// ```
///
/// `NA` must be NX + [`ControllerSettings::n_states`]: stable Rust cannot write the sum as a
/// const argument, so `NA ≥ NX` is checked at compile time and the equality by [`PidLoop::new`].
/// The Jacobian is exact: derivatives of the setpoint (0.03 sin Φ), the outer loops and the
/// anti-windup branch are all included; at a saturation or anti-windup switch the derivative of
/// the active branch is used (the almost-everywhere Jacobian the Lyapunov exponents need).
#[derive(Debug)]
pub struct PidLoop<'a, M, const NX: usize, const NU: usize, const NA: usize> {
    model: &'a M,
    settings: &'a ControllerSettings,
    plant: Plant<NU>,
    layout: Layout,
}

// By hand: derives would require `M: Clone`, but only references are copied.
impl<M, const NX: usize, const NU: usize, const NA: usize> Clone for PidLoop<'_, M, NX, NU, NA> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<M, const NX: usize, const NU: usize, const NA: usize> Copy for PidLoop<'_, M, NX, NU, NA> {}

/// e_i as a row.
#[inline(always)]
fn unit<const N: usize>(i: usize) -> [f64; N] {
    with_entry([0.0; N], i, 1.0)
}

/// `a` with entry `i` replaced by `v`, written as a select over every entry rather than a
/// store at a run-time index: the law's rows are read back as vectors right after, and a
/// narrow store read by a wide load stalls store forwarding (the select form took the 100×100
/// Lyapunov map from 15.7 to 14.6 s).
#[inline(always)]
fn with_entry<const N: usize>(a: [f64; N], i: usize, v: f64) -> [f64; N] {
    core::array::from_fn(|j| if j == i { v } else { a[j] })
}

/// `a` with `v` added to entry `i` (`a[i] += v` in the select form of [`with_entry`]).
#[inline(always)]
fn plus_entry<const N: usize>(a: [f64; N], i: usize, v: f64) -> [f64; N] {
    core::array::from_fn(|j| if j == i { a[j] + v } else { a[j] })
}

/// a += c b.
#[inline(always)]
fn axpy<const N: usize>(a: &mut [f64; N], c: f64, b: &[f64; N]) {
    for (a, b) in a.iter_mut().zip(b) {
        *a += c * b;
    }
}

#[inline(always)]
fn dot<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

impl<'a, M, const NX: usize, const NU: usize, const NA: usize> PidLoop<'a, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    /// The closed loop of `model` with `settings` through `plant` (see [`Plant::from_info`]).
    pub fn new(
        model: &'a M,
        settings: &'a ControllerSettings,
        plant: Plant<NU>,
    ) -> Result<Self, ControlError> {
        const { assert!(NA >= NX, "the augmented size NA must be ≥ NX") };
        settings.validate()?;
        let nz = settings.n_states();
        if NA != NX + nz {
            return Err(ControlError::AugmentedSize { na: NA, nx: NX, nz });
        }
        let info = model.info();
        let missing = |state| ControlError::MissingState {
            model: info.name.to_string(),
            state,
            states: info.states.join(", "),
        };
        if settings.velocity.is_some() && plant.measured.v_x.is_none() {
            return Err(missing("v_x"));
        }
        if settings.yaw.is_some() {
            if plant.measured.w_z.is_none() {
                return Err(missing("w_z"));
            }
            if plant.inputs.yaw.is_none() {
                return Err(ControlError::NoYawInput {
                    model: info.name.to_string(),
                });
            }
        }
        Ok(Self {
            model,
            settings,
            plant,
            layout: Layout::new(settings, NX),
        })
    }

    /// The model.
    pub fn model(&self) -> &'a M {
        self.model
    }

    /// The controller settings.
    pub fn settings(&self) -> &'a ControllerSettings {
        self.settings
    }

    /// The plant view (measured states, input map).
    pub fn plant(&self) -> &Plant<NU> {
        &self.plant
    }

    /// Where the controller states are.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The augmented initial state: the model state `x0`, zero integrals, and the rate filter
    /// at the measured rate (a filter that has been running, so no start-up transient).
    pub fn initial_state(&self, x0: &[f64; NX]) -> [f64; NA] {
        let mut xa = [0.0; NA];
        xa[..NX].copy_from_slice(x0);
        if let Some(i) = self.layout.filter {
            xa[i] = x0[self.plant.measured.w_y];
        }
        xa
    }

    /// What the controller commands at (t, x_aug).
    pub fn command(&self, t: f64, xa: &[f64; NA]) -> Command<NU> {
        self.law::<false>(t, xa).cmd
    }

    /// The law at (t, x_aug); the gradients only when `GRAD` (the hot loop without tangents
    /// skips them).
    #[inline(always)]
    fn law<const GRAD: bool>(&self, t: f64, xa: &[f64; NA]) -> Law<NA, NU> {
        let setpoint = self
            .settings
            .pitch
            .setpoint
            .eval(xa[self.plant.measured.phi]);
        self.law_at::<GRAD>(t, xa, setpoint)
    }

    /// [`law`](Self::law) with the setpoint (Φ_ref(Φ), dΦ_ref/dΦ) already evaluated (the maps
    /// evaluate eight at once).
    #[inline(always)]
    fn law_at<const GRAD: bool>(
        &self,
        t: f64,
        xa: &[f64; NA],
        setpoint: (f64, f64),
    ) -> Law<NA, NU> {
        let s = self.settings;
        let p = &s.pitch;
        let g = &p.gains;
        let m = &self.plant.measured;
        let lay = &self.layout;
        let zero = [0.0; NA];

        // Setpoint, with the velocity loop's lean.
        let phi = xa[m.phi];
        let (mut phi_ref, dsp) = setpoint;
        let mut d_ref = zero;
        if GRAD {
            d_ref = with_entry(d_ref, m.phi, dsp);
        }
        let mut zdot = [0.0; 3];
        let mut d_zdot = [zero; 3];
        if let (Some(vl), Some(iv)) = (&s.velocity, m.v_x) {
            let v = self.velocity_lean::<GRAD>(vl, iv, t, xa);
            phi_ref += v.lean;
            zdot[2] = v.zdot;
            if GRAD {
                axpy(&mut d_ref, 1.0, &v.d_lean);
                d_zdot[2] = v.d_zdot;
            }
        }
        let e = phi - phi_ref;
        let mut de = zero;
        if GRAD {
            de = unit(m.phi);
            axpy(&mut de, -1.0, &d_ref);
        }

        // Force command: derivative on the (optionally filtered) measured rate.
        let rate_index = lay.filter.unwrap_or(m.w_y);
        let mut force_cmd = g.kp * e + g.kd * xa[rate_index];
        let mut d_cmd = zero;
        if GRAD {
            axpy(&mut d_cmd, g.kp, &de);
            d_cmd = plus_entry(d_cmd, rate_index, g.kd);
        }
        if let Some(iz) = lay.integral {
            force_cmd += g.ki * xa[iz];
            if GRAD {
                d_cmd = plus_entry(d_cmd, iz, g.ki);
            }
        }
        if let (Some(tau), Some(iz)) = (p.derivative_filter, lay.filter) {
            zdot[1] = (xa[m.w_y] - xa[iz]) / tau;
            if GRAD {
                d_zdot[1] = with_entry(d_zdot[1], m.w_y, 1.0 / tau);
                d_zdot[1] = with_entry(d_zdot[1], iz, -1.0 / tau);
            }
        }

        // Saturation: the active branch's derivative.
        let (force, saturated) = match p.saturation {
            Some(fm) if force_cmd > fm => (fm, true),
            Some(fm) if force_cmd < -fm => (-fm, true),
            _ => (force_cmd, false),
        };
        let d_force = if saturated || !GRAD { zero } else { d_cmd };

        // Integral with anti-windup.
        if lay.integral.is_some() {
            match p.anti_windup {
                AntiWindup::Conditional if saturated && e * force_cmd > 0.0 => {}
                AntiWindup::BackCalculation { tracking_time } => {
                    let c = 1.0 / (g.ki * tracking_time);
                    zdot[0] = e + c * (force - force_cmd);
                    if GRAD {
                        d_zdot[0] = de;
                        axpy(&mut d_zdot[0], c, &d_force);
                        axpy(&mut d_zdot[0], -c, &d_cmd);
                    }
                }
                _ => {
                    zdot[0] = e;
                    if GRAD {
                        d_zdot[0] = de;
                    }
                }
            }
        }

        // Yaw-rate loop.
        let mut yaw = 0.0;
        let mut d_yaw = zero;
        if let (Some(yl), Some(iw)) = (&s.yaw, m.w_z) {
            yaw = yl.kp * (yl.reference.value(t) - xa[iw]);
            if GRAD {
                d_yaw = with_entry(d_yaw, iw, -yl.kp);
            }
        }

        let fdir = &self.plant.inputs.force;
        let ydir = self.plant.inputs.yaw.unwrap_or([0.0; NU]);
        let u = core::array::from_fn(|j| fdir[j] * force + ydir[j] * yaw);
        Law {
            cmd: Command {
                phi_ref,
                force_cmd,
                force,
                yaw,
                saturated,
                u,
            },
            d_force,
            d_yaw,
            zdot,
            d_zdot,
        }
    }

    /// The velocity loop's lean request at (t, x_aug) and the ż of its integral, with their
    /// rows when `GRAD`. Out of line: the sweeps' laws have no velocity loop, and this branch
    /// inlined into them cost ~4 % of a map.
    #[inline(never)]
    fn velocity_lean<const GRAD: bool>(
        &self,
        vl: &VelocityLoop,
        iv: usize,
        t: f64,
        xa: &[f64; NA],
    ) -> Lean<NA> {
        let zero = [0.0; NA];
        let ev = vl.reference.value(t) - xa[iv];
        let mut v = Lean {
            lean: vl.kp * ev,
            d_lean: zero,
            zdot: 0.0,
            d_zdot: zero,
        };
        if GRAD {
            v.d_lean = with_entry(zero, iv, -vl.kp);
        }
        if let Some(iz) = self.layout.velocity_integral {
            v.lean += vl.ki * xa[iz];
            v.zdot = ev;
            if GRAD {
                v.d_lean = plus_entry(v.d_lean, iz, vl.ki);
                v.d_zdot = with_entry(zero, iv, -1.0);
            }
        }
        // Lean limit: the active branch's derivative (zero while limited), and the integral
        // holds while the error pushes further into the limit.
        if let Some(lm) = vl.lean_max {
            if v.lean.abs() > lm {
                v.lean = lm.copysign(v.lean);
                v.d_lean = zero;
                if ev * v.lean > 0.0 {
                    v.zdot = 0.0;
                    v.d_zdot = zero;
                }
            }
        }
        v
    }

    /// The controller states present as (absolute index, slot in `zdot`).
    #[inline(always)]
    fn slots(&self) -> [(Option<usize>, usize); 3] {
        [
            (self.layout.integral, 0),
            (self.layout.filter, 1),
            (self.layout.velocity_integral, 2),
        ]
    }

    /// ∂u/∂x_aug w for one tangent vector.
    #[inline(always)]
    fn du(&self, law: &Law<NA, NU>, w: &[f64; NA]) -> [f64; NU] {
        let (df, dt) = (dot(&law.d_force, w), dot(&law.d_yaw, w));
        let fdir = &self.plant.inputs.force;
        let ydir = self.plant.inputs.yaw.unwrap_or([0.0; NU]);
        core::array::from_fn(|j| fdir[j] * df + ydir[j] * dt)
    }

    /// What J·w needs of the law for one tangent vector: ∂u/∂x_aug·w and the controller
    /// rows ∂ż/∂x_aug·w (slot order of [`Layout`]).
    #[inline(always)]
    fn tangent(&self, law: &Law<NA, NU>, w: &[f64; NA]) -> Tangent<NU> {
        let mut dz = [0.0; 3];
        for (iz, slot) in self.slots() {
            if iz.is_some() {
                dz[slot] = dot(&law.d_zdot[slot], w);
            }
        }
        Tangent {
            du: self.du(law, w),
            dz,
        }
    }

    /// F and J·w of the closed loop from the controller's ż, the law's tangents and the
    /// model's f, (∂f/∂x)·w and ∂f/∂u at the same point (`jwx` empty when K = 0).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn assemble<const K: usize>(
        &self,
        zdot: &[f64; 3],
        tangents: &[Tangent<NU>],
        fx: &[f64; NX],
        jwx: &[[f64; NX]],
        b: &[[f64; NU]; NX],
        f: &mut [f64; NA],
        jw: &mut [[f64; NA]; K],
    ) {
        for ((out, tan), jx) in jw.iter_mut().zip(tangents).zip(jwx) {
            for i in 0..NX {
                out[i] = jx[i] + dot(&b[i], &tan.du);
            }
            for (iz, slot) in self.slots() {
                if let Some(iz) = iz {
                    out[iz] = tan.dz[slot];
                }
            }
        }
        f[..NX].copy_from_slice(fx);
        for (iz, slot) in self.slots() {
            if let Some(iz) = iz {
                f[iz] = zdot[slot];
            }
        }
    }
}

impl<M, const NX: usize, const NU: usize, const NA: usize> VectorField<NA>
    for PidLoop<'_, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    const COMPILED_IN: bool = M::COMPILED_IN;

    #[inline(always)]
    fn eval<const K: usize>(
        &self,
        t: f64,
        xa: &[f64; NA],
        w: &[[f64; NA]; K],
        f: &mut [f64; NA],
        jw: &mut [[f64; NA]; K],
    ) {
        let x: [f64; NX] = core::array::from_fn(|i| xa[i]);
        let mut fx = [0.0; NX];
        if K == 0 {
            let law = self.law::<false>(t, xa);
            self.model.f(&x, &law.cmd.u, &mut fx);
            self.assemble::<K>(&law.zdot, &[], &fx, &[], &[[0.0; NU]; NX], f, jw);
        } else {
            let law = self.law::<true>(t, xa);
            let tangents: [Tangent<NU>; K] = core::array::from_fn(|k| self.tangent(&law, &w[k]));
            let wx: [[f64; NX]; K] = core::array::from_fn(|k| core::array::from_fn(|i| w[k][i]));
            let mut jwx = [[0.0; NX]; K];
            let mut b = [[0.0; NU]; NX];
            self.model
                .f_jw_jac_u(&x, &law.cmd.u, &wx, &mut fx, &mut jwx, &mut b);
            self.assemble::<K>(&law.zdot, &tangents, &fx, &jwx, &b, f, jw);
        }
    }

    /// tr J = tr f_x + Σ_i (f_u ∂u/∂x_i)_i + Σ_z ∂ż/∂z: one dense `jac_x` and one `jac_u`
    /// instead of NA directional derivatives.
    fn trace_jacobian(&self, t: f64, xa: &[f64; NA]) -> f64 {
        let x: [f64; NX] = core::array::from_fn(|i| xa[i]);
        let law = self.law::<true>(t, xa);
        let mut jx = [[0.0; NX]; NX];
        let mut b = [[0.0; NU]; NX];
        self.model.jac_x(&x, &law.cmd.u, &mut jx);
        self.model.jac_u(&x, &law.cmd.u, &mut b);
        let mut tr = 0.0;
        for i in 0..NX {
            let du = self.du(&law, &unit(i));
            tr += jx[i][i] + dot(&b[i], &du);
        }
        for (iz, slot) in self.slots() {
            if let Some(iz) = iz {
                tr += law.d_zdot[slot][iz];
            }
        }
        tr
    }
}
