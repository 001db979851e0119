//! The closed loops of [`LANES`] grid points evaluated together, for the maps, on lane arrays
//! ([`LaneStates`]): the model runs through its lanes kernel
//! ([`Model::f_jw_jac_u_lane_arrays`]) and the laws either one loop after the other (any
//! controller) or, for the maps' common case of a plain PD law, as lane arrays.
//! Every lane has the bits of [`VectorField::eval`](crate::integrate::VectorField::eval) of its
//! loop alone (`tests/tests/all/sweep_lanes.rs` checks each case).

use twv_kernels::lanes::{Lanes, LANES};
use twv_model::Model;

use super::PidLoop;
use crate::control::settings::Setpoint;
use crate::integrate::{one_row, LaneStates};

/// The lane (sin Φ, cos Φ) a sine setpoint takes, which the lanes kernel can take too.
type SinCos = (Lanes, Lanes);

/// Eight closed loops of one model, evaluated together with one tangent vector each.
pub struct LoopLanes<'a, M, const NX: usize, const NU: usize, const NA: usize> {
    loops: [PidLoop<'a, M, NX, NU, NA>; LANES],
    /// The laws as lane arrays, when every loop is a plain PD law of the same plant.
    pd: Option<PdLanes<NU>>,
    /// ∂f/∂u of the lanes, which the kernel writes whole at every evaluation: kept here so
    /// that no evaluation spends ~70 instructions zeroing it first.
    b: [[Lanes; NU]; NX],
}

/// A plain PD law (no controller state, no outer loop) at eight loops of one plant:
/// F = sat(Kp (Φ − Φ_ref(Φ)) + Kd Φ̇), u = F·force_dir, lane `l` with loop `l`'s gains.
struct PdLanes<const NU: usize> {
    phi: usize,
    rate: usize,
    kp: Lanes,
    kd: Lanes,
    /// F_max, +∞ without saturation (no command exceeds it: the same branch as `None`).
    force_max: Lanes,
    force_dir: [f64; NU],
    yaw_dir: [f64; NU],
    setpoint: SetpointLanes,
}

/// The eight loops' setpoints as lane arrays, all of one kind: Φ_ref and dΦ_ref/dΦ are then
/// whole-lane operations, which lets the law around them vectorise too (one setpoint per lane
/// read through its enum made the whole law scalar, the largest block of the maps' driver).
#[derive(Clone, Copy)]
enum SetpointLanes {
    /// Φ_ref = value, dΦ_ref/dΦ = 0 ([`Setpoint::Zero`] is the value 0).
    Fixed { value: Lanes },
    /// Φ_ref = A·sin Φ, dΦ_ref/dΦ = A·cos Φ.
    Sine { amplitude: Lanes },
}

impl SetpointLanes {
    /// The lane arrays of `setpoints`, if they are all fixed or all sines.
    fn new(setpoints: [Setpoint; LANES]) -> Option<Self> {
        let fixed = |s: &Setpoint| match *s {
            Setpoint::Zero => Some(0.0),
            Setpoint::Constant { value } => Some(value),
            Setpoint::Sine { .. } => None,
        };
        let sine = |s: &Setpoint| match *s {
            Setpoint::Sine { amplitude } => Some(amplitude),
            _ => None,
        };
        let all = |f: &dyn Fn(&Setpoint) -> Option<f64>| {
            let values = setpoints.map(|s| f(&s));
            values
                .iter()
                .all(Option::is_some)
                .then(|| values.map(|v| v.unwrap_or(0.0)))
        };
        (all(&fixed).map(|value| Self::Fixed { value }))
            .or_else(|| all(&sine).map(|amplitude| Self::Sine { amplitude }))
    }

    /// Φ_ref and dΦ_ref/dΦ of every lane at its Φ: the bits of [`Setpoint::eval`]; and the
    /// lane (sin Φ, cos Φ) if the setpoint took them.
    #[inline(always)]
    fn eval(&self, phi: &Lanes) -> (Lanes, Lanes, Option<SinCos>) {
        match self {
            Self::Fixed { value } => (*value, [0.0; LANES], None),
            Self::Sine { amplitude } => {
                let (s, c) = twv_kernels::lanes::sin_cos(*phi);
                let (mut phi_ref, mut slope) = ([0.0; LANES], [0.0; LANES]);
                for l in 0..LANES {
                    (phi_ref[l], slope[l]) = (amplitude[l] * s[l], amplitude[l] * c[l]);
                }
                (phi_ref, slope, Some((s, c)))
            }
        }
    }
}

impl<'a, M, const NX: usize, const NU: usize, const NA: usize> LoopLanes<'a, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    /// The loops `loops`, all of the same model.
    pub fn new(loops: [PidLoop<'a, M, NX, NU, NA>; LANES]) -> Self {
        let pd = Self::pd_lanes(&loops);
        let b = [[[0.0; LANES]; NU]; NX];
        Self { loops, pd, b }
    }

    /// Lane `lane` runs `lp` from now on (a loop of the same model).
    pub fn set(&mut self, lane: usize, lp: PidLoop<'a, M, NX, NU, NA>) {
        self.loops[lane] = lp;
        self.pd = Self::pd_lanes(&self.loops);
    }

    /// The lane-array PD law of `loops`, if every one is a plain PD law of the same plant (Φ and
    /// Φ̇ two states) with a finite Kp (as validated settings have) and their setpoints are all
    /// fixed or all sines.
    fn pd_lanes(loops: &[PidLoop<'a, M, NX, NU, NA>; LANES]) -> Option<PdLanes<NU>> {
        debug_assert!(loops.iter().all(|l| core::ptr::eq(l.model, loops[0].model)));
        let plain = |l: &PidLoop<'a, M, NX, NU, NA>| {
            let s = l.settings;
            l.layout.states().is_empty()
                && s.pitch.gains.kp.is_finite()
                && l.plant.measured.phi != l.plant.measured.w_y
                && s.velocity.is_none()
                && s.yaw.is_none()
                && l.plant == loops[0].plant
        };
        let setpoint = SetpointLanes::new(loops.map(|l| l.settings.pitch.setpoint))?;
        loops.iter().all(plain).then(|| {
            let plant = &loops[0].plant;
            let gains = loops.map(|l| l.settings.pitch.gains);
            PdLanes {
                phi: plant.measured.phi,
                rate: plant.measured.w_y,
                kp: gains.map(|g| g.kp),
                kd: gains.map(|g| g.kd),
                force_max: loops.map(|l| l.settings.pitch.saturation.unwrap_or(f64::INFINITY)),
                force_dir: plant.inputs.force,
                yaw_dir: plant.inputs.yaw.unwrap_or([0.0; NU]),
                setpoint,
            }
        })
    }

    /// [`VectorField::eval`](crate::integrate::VectorField::eval) with one tangent vector for
    /// every loop at once (loop `l` at time `t[l]` and point `l` of `y` → point `l` of `dy`),
    /// all on lane arrays: the laws (for a plain PD law), the lanes kernel and the assembly of
    /// the closed loop's derivatives are whole-lane operations.
    #[inline(always)]
    pub fn eval(
        &mut self,
        t: &[f64; LANES],
        y: &LaneStates<NA, LANES>,
        dy: &mut LaneStates<NA, LANES>,
    ) {
        let mut u = [[0.0; LANES]; NU];
        let mut du = [[0.0; LANES]; NU];
        // A sine setpoint takes the pitch's lane (sin, cos), and so may the lanes kernel: it is
        // computed once, for both, on either path (the maps' kernel took the pitch's three
        // times a stage).
        let pitch_sin_cos = match &self.pd {
            Some(pd) => pd.eval(y, &mut u, &mut du),
            None => {
                let phi = self.loops[0].plant.measured.phi;
                let (setpoints, sin_cos) = self.setpoints(&y.x[phi]);
                for (l, lp) in self.loops.iter().enumerate() {
                    let point = y.point(l);
                    // Reduced at once to what is needed later: copying eight whole laws (their
                    // gradient rows) costs more than the model itself.
                    let law = lp.law_at::<true>(t[l], &point.x, setpoints[l]);
                    let tangent = lp.tangent(&law, &point.w[0]);
                    for k in 0..NU {
                        (u[k][l], du[k][l]) = (law.cmd.u[k], tangent.du[k]);
                    }
                    for (iz, slot) in lp.slots() {
                        if let Some(iz) = iz {
                            (dy.x[iz][l], dy.w[iz][l]) = (law.zdot[slot], tangent.dz[slot]);
                        }
                    }
                }
                sin_cos.map(|sc| (phi, sc))
            }
        };
        let x: &[Lanes; NX] = y.x[..NX].try_into().expect("NX ≤ NA");
        let w: &[Lanes; NX] = y.w[..NX].try_into().expect("NX ≤ NA");
        let (fx, jwx): (&mut [Lanes; NX], &mut [Lanes; NX]) = (
            (&mut dy.x[..NX]).try_into().expect("NX ≤ NA"),
            (&mut dy.w[..NX]).try_into().expect("NX ≤ NA"),
        );
        let (b, model) = (&mut self.b, self.loops[0].model);
        match &pitch_sin_cos {
            Some(sc) => model.f_jw_jac_u_lane_arrays_given(x, &u, w, fx, jwx, b, (sc.0, &sc.1)),
            None => model.f_jw_jac_u_lane_arrays(x, &u, w, fx, jwx, b),
        }
        // J·w of the loop: the model's plus ∂f/∂u · ∂u/∂x·w, the dot product as `assemble`
        // forms it (every term added to `-0.0`, the start of `f64`'s `Sum`).
        for (out, b) in jwx.iter_mut().zip(&*b) {
            let out = one_row(out);
            let mut row = *out;
            for l in 0..LANES {
                let mut sum = -0.0;
                for k in 0..NU {
                    sum += b[k][l] * du[k][l];
                }
                row[l] += sum;
            }
            *out = row;
        }
    }

    /// Each loop's setpoint at its Φ (`phi`), as [`Setpoint::eval`] gives it, with the sines of
    /// all eight from one lane-wise sincos (the same bits) when any loop's setpoint needs one;
    /// and that lane (sin Φ, cos Φ) if it was taken.
    #[inline(always)]
    fn setpoints(&self, phi: &Lanes) -> ([(f64, f64); LANES], Option<SinCos>) {
        let sine = |l: &PidLoop<'a, M, NX, NU, NA>| {
            matches!(l.settings.pitch.setpoint, Setpoint::Sine { .. })
        };
        let sin_cos = self
            .loops
            .iter()
            .any(sine)
            .then(|| twv_kernels::lanes::sin_cos(*phi));
        let (s, c) = sin_cos.unwrap_or(([0.0; LANES], [0.0; LANES]));
        let mut out = [(0.0, 0.0); LANES];
        for l in 0..LANES {
            out[l] = self.loops[l]
                .settings
                .pitch
                .setpoint
                .eval_with(|| (s[l], c[l]));
        }
        (out, sin_cos)
    }
}

impl<const NU: usize> PdLanes<NU> {
    /// u and ∂u/∂x·w of every lane (`u[k][l]`, `du[k][l]`), and the lane (sin, cos) of Φ if the
    /// setpoint took it, with Φ's state index (for the kernel). The operations of
    /// [`PidLoop::law_at`] and [`PidLoop::tangent`] for this law, entry by entry in the same
    /// order, with the gradient rows never stored: row entries that are zero there are the same
    /// `+0` here, and the dot products still add every term from `-0.0` (the start of `f64`'s
    /// `Sum`), so even the signs of zeros and NaNs come out as in the one-loop path.
    #[inline(always)]
    fn eval<const NA: usize>(
        &self,
        y: &LaneStates<NA, LANES>,
        u: &mut [Lanes; NU],
        du: &mut [Lanes; NU],
    ) -> Option<(usize, SinCos)> {
        let (phi, rate) = (&y.x[self.phi], &y.x[self.rate]);
        let (phi_ref, dsp, sin_cos) = self.setpoint.eval(phi);
        let mut force = [0.0; LANES];
        let mut saturated = [false; LANES];
        let mut de_phi = [0.0; LANES];
        for l in 0..LANES {
            let (phi_ref, dsp) = (phi_ref[l], dsp[l]);
            let e = phi[l] - phi_ref;
            // unit(Φ) − ∂Φ_ref/∂x at Φ's entry, as the one-loop path forms it (elsewhere
            // 0 + (−1)·0 = +0). `-dsp` would differ from `-1.0 * dsp` in the sign of a NaN.
            #[allow(clippy::neg_multiply)]
            let d = 1.0 + -1.0 * dsp;
            de_phi[l] = d;
            let cmd = self.kp[l] * e + self.kd[l] * rate[l];
            // `law_at`'s clamp (above F_max: F_max, else below −F_max: −F_max, else the
            // command, NaN included) as two selects, which vectorise across the lanes.
            let fm = self.force_max[l];
            let (above, below) = (cmd > fm, cmd < -fm);
            let clamped = if below { -fm } else { cmd };
            force[l] = if above { fm } else { clamped };
            saturated[l] = above | below;
        }
        // ∂F/∂x·w and ∂(yaw)/∂x·w. The gradient of F (the command's, zero while saturated) is
        // +0 at every entry but Φ and Φ̇ (0 + Kp·0 with a finite Kp, see `pd_lanes`), the yaw's
        // +0 at all: those terms are +0·w, the same for both sums, added first. That gives the
        // bits of the dot products in index order: a signed zero term changes only a zero sum's
        // sign, in any order (a sum of zeros is −0 only if every term is), and a non-finite w
        // makes both NaN either way.
        let mut zeros = [-0.0; LANES];
        for (j, w) in y.w.iter().enumerate() {
            if j != self.phi && j != self.rate {
                let w = *one_row(w);
                for l in 0..LANES {
                    zeros[l] += 0.0 * w[l];
                }
            }
        }
        let (mut d_force_w, mut d_yaw_w) = (zeros, zeros);
        let (first, second) = (self.phi.min(self.rate), self.phi.max(self.rate));
        for j in [first, second] {
            let w = *one_row(&y.w[j]);
            for l in 0..LANES {
                let de = if j == self.phi { de_phi[l] } else { 0.0 };
                let mut d_cmd = 0.0 + self.kp[l] * de;
                if j == self.rate {
                    d_cmd += self.kd[l];
                }
                let d_force = if saturated[l] { 0.0 } else { d_cmd };
                d_force_w[l] += d_force * w[l];
                d_yaw_w[l] += 0.0 * w[l];
            }
        }
        let (fdir, ydir) = (&self.force_dir, &self.yaw_dir);
        for k in 0..NU {
            for l in 0..LANES {
                u[k][l] = fdir[k] * force[l] + ydir[k] * 0.0;
                du[k][l] = fdir[k] * d_force_w[l] + ydir[k] * d_yaw_w[l];
            }
        }
        sin_cos.map(|sc| (self.phi, sc))
    }
}
