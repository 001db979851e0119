//! The adaptive Dormand–Prince 5(4) pair with its continuous extension (Hairer–Nørsett–Wanner,
//! Solving ODEs I, §II.5 and the `dopri5` code): 7 stages, first-same-as-last, local
//! extrapolation (the 5th-order solution is propagated), a PI step-size controller and 4th-order
//! dense output.

use serde::{Deserialize, Serialize};

use super::state::eval_stage;
use super::stepper::{check_initial, check_stop};
use super::{IntegrateError, Stepper, StopReason, VarState, VectorField};

// Butcher tableau.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error weights: y5 − y4 = h Σ E_i k_i.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output (Shampine's 4th-order continuous extension as in Hairer's dopri5).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Options of [`Dopri5`]. Defaults are beside each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DopriOptions {
    /// Relative tolerance. Default 1e-9.
    pub rtol: f64,
    /// Absolute tolerance. Default 1e-12.
    pub atol: f64,
    /// Include the tangent vectors in the error norm. Default false: the step size then depends
    /// on x only, as for the plain ODE; turn it on when the tangent dynamics is stiffer than the
    /// trajectory (the exponents then carry the requested accuracy too).
    pub tangent_error_control: bool,
    /// First step size; `None` (default) picks it from the problem (Hairer's `hinit`).
    pub h_init: Option<f64>,
    /// Largest step size. Default ∞.
    pub h_max: f64,
    /// Smallest step size before [`IntegrateError::StepSizeUnderflow`]. Default 0 (only the
    /// resolution of t limits it).
    pub h_min: f64,
    /// Safety factor of the controller. Default 0.9.
    pub safety: f64,
    /// Smallest step-size ratio per step. Default 0.2.
    pub fac_min: f64,
    /// Largest step-size ratio per step. Default 10.
    pub fac_max: f64,
    /// PI stabilisation exponent (0 = plain I controller). Default 0.04, Hairer's value.
    pub beta: f64,
    /// Most steps (accepted and rejected) before [`IntegrateError::TooManySteps`]. Default
    /// [`MAX_STEPS`](super::MAX_STEPS).
    pub max_steps: u64,
}

impl Default for DopriOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-9,
            atol: 1e-12,
            tangent_error_control: false,
            h_init: None,
            h_max: f64::INFINITY,
            h_min: 0.0,
            safety: 0.9,
            fac_min: 0.2,
            fac_max: 10.0,
            beta: 0.04,
            max_steps: super::MAX_STEPS,
        }
    }
}

impl DopriOptions {
    /// Checks every option; the error names the first bad one.
    pub fn validate(&self) -> Result<(), IntegrateError> {
        let bad = |what: &str| Err(IntegrateError::InvalidOption(what.to_string()));
        if !(self.rtol.is_finite() && self.rtol >= 0.0 && self.atol.is_finite() && self.atol >= 0.0)
            || self.rtol + self.atol <= 0.0
        {
            return bad(&format!(
                "tolerances rtol = {}, atol = {} must be finite, ≥ 0, not both 0",
                self.rtol, self.atol
            ));
        }
        if let Some(h) = self.h_init {
            if !(h.is_finite() && h > 0.0) {
                return bad(&format!("h_init = {h} must be finite and > 0"));
            }
        }
        if !(self.h_max > 0.0 && self.h_min >= 0.0 && self.h_min < self.h_max) {
            return bad(&format!(
                "step bounds h_min = {}, h_max = {} need 0 ≤ h_min < h_max, h_max > 0",
                self.h_min, self.h_max
            ));
        }
        if !(self.safety > 0.0 && self.safety <= 1.0) {
            return bad(&format!("safety = {} must be in (0, 1]", self.safety));
        }
        if !(self.fac_min > 0.0
            && self.fac_min < 1.0
            && self.fac_max > 1.0
            && self.fac_max.is_finite())
        {
            return bad(&format!(
                "step ratio bounds fac_min = {}, fac_max = {} need 0 < fac_min < 1 < fac_max < ∞",
                self.fac_min, self.fac_max
            ));
        }
        if !(0.0..0.2).contains(&self.beta) {
            return bad(&format!("beta = {} must be in [0, 0.2)", self.beta));
        }
        if self.max_steps == 0 || self.max_steps > super::MAX_STEPS {
            return bad(&format!(
                "max_steps = {} must be in 1..={}",
                self.max_steps,
                super::MAX_STEPS
            ));
        }
        Ok(())
    }
}

/// Adaptive Dormand–Prince 5(4) on the variational system, with dense output.
///
/// The field is all that is generic over the model: every other part of a step (the stage
/// combinations, the error norm, the step-size controller) is [`DopriCore`], compiled once per
/// `(N, K)` and handed the stage evaluation as a `dyn` callback. The jobs build a stepper for
/// dozens of field types; compiled per field, those parts were the analysis crate's largest
/// code (1.1 MB of 7.6) for one indirect call per stage, a few nanoseconds beside a stage.
#[derive(Debug, Clone)]
pub struct Dopri5<F, const N: usize, const K: usize> {
    field: F,
    trace: bool,
    core: DopriCore<N, K>,
}

/// One stage evaluation: `dy = (F, J w, tr J)` at `(t, y)`.
type StageEval<'a, const N: usize, const K: usize> =
    dyn FnMut(f64, &VarState<N, K>, &mut VarState<N, K>) + 'a;

/// The state and the logic of a [`Dopri5`] stepper apart from its field.
#[derive(Debug, Clone)]
struct DopriCore<const N: usize, const K: usize> {
    opts: DopriOptions,
    t: f64,
    /// Proposed size of the next step (`None` until the first step chooses one).
    h_next: Option<f64>,
    t_stop: Option<f64>,
    /// `k[0]` holds F(t, y) for the current point.
    k1_current: bool,
    /// `k[6]` holds F(t, y) for the current point (first same as last).
    k7_current: bool,
    /// The last step can be interpolated (no tangent replacement since).
    dense_valid: bool,
    last_rejected: bool,
    /// Previous accepted error (PI controller memory).
    err_old: f64,
    steps: u64,
    rejected: u64,
    evals: u64,
    /// Start time and size of the last accepted step.
    t_old: f64,
    h_last: f64,
    y: VarState<N, K>,
    y_old: VarState<N, K>,
    y_new: VarState<N, K>,
    tmp: VarState<N, K>,
    k: [VarState<N, K>; 7],
}

impl<F: VectorField<N>, const N: usize, const K: usize> Dopri5<F, N, K> {
    /// A stepper at `(t0, x0, w0)`; `trace` turns on the ∫ tr J quadrature (integrated with the
    /// same stages, not part of the error norm).
    pub fn new(
        field: F,
        t0: f64,
        x0: [f64; N],
        w0: [[f64; N]; K],
        opts: DopriOptions,
        trace: bool,
    ) -> Result<Self, IntegrateError> {
        opts.validate()?;
        let y = VarState::new(x0, w0);
        check_initial(t0, &y)?;
        Ok(Self {
            field,
            trace,
            core: DopriCore {
                opts,
                t: t0,
                h_next: opts.h_init,
                t_stop: None,
                k1_current: false,
                k7_current: false,
                dense_valid: false,
                last_rejected: false,
                err_old: 1e-4,
                steps: 0,
                rejected: 0,
                evals: 0,
                t_old: t0,
                h_last: 0.0,
                y,
                y_old: y,
                y_new: y,
                tmp: VarState::ZERO,
                k: [VarState::ZERO; 7],
            },
        })
    }

    /// Rejected steps so far.
    pub fn rejected_steps(&self) -> u64 {
        self.core.rejected
    }

    /// Stage evaluations so far.
    pub fn evaluations(&self) -> u64 {
        self.core.evals
    }

    /// The step size the controller proposes next (after the first step).
    pub fn proposed_step(&self) -> Option<f64> {
        self.core.h_next
    }

    /// The interval `[t_start, t_end]` of the last accepted step while dense output is valid.
    pub fn last_step(&self) -> Option<(f64, f64)> {
        self.core
            .dense_valid
            .then_some((self.core.t_old, self.core.t_old + self.core.h_last))
    }

    /// The solution at `t` inside the last accepted step, from the 4th-order continuous
    /// extension (state, tangents and trace quadrature). Invalid after
    /// [`set_tangents`](Stepper::set_tangents), which replaces the tangents the step ended with.
    pub fn interpolate(&self, t: f64, out: &mut VarState<N, K>) -> Result<(), IntegrateError> {
        self.core.interpolate(t, out)
    }
}

impl<const N: usize, const K: usize> DopriCore<N, K> {
    /// See [`Dopri5::interpolate`].
    #[inline(never)]
    fn interpolate(&self, t: f64, out: &mut VarState<N, K>) -> Result<(), IntegrateError> {
        let t_end = self.t_old + self.h_last;
        if !(self.dense_valid && t >= self.t_old && t <= t_end) {
            return Err(IntegrateError::OutsideLastStep {
                t,
                t_start: self.t_old,
                t_end: if self.dense_valid { t_end } else { f64::NAN },
            });
        }
        let h = self.h_last;
        let th = (t - self.t_old) / h;
        let th1 = 1.0 - th;
        let [k1, _, k3, k4, k5, k6, k7] = &self.k;
        // y(θ) = y0 + θ(Δ + (1−θ)(b + θ(Δ − h k7 − b + (1−θ) h Σ d_i k_i))), b = h k1 − Δ.
        let comp = |y0: f64, y1: f64, k1: f64, k3: f64, k4: f64, k5: f64, k6: f64, k7: f64| {
            let dy = y1 - y0;
            let b = h * k1 - dy;
            let r5 = h * (D1 * k1 + D3 * k3 + D4 * k4 + D5 * k5 + D6 * k6 + D7 * k7);
            y0 + th * (dy + th1 * (b + th * (dy - h * k7 - b + th1 * r5)))
        };
        for i in 0..N {
            out.x[i] = comp(
                self.y_old.x[i],
                self.y.x[i],
                k1.x[i],
                k3.x[i],
                k4.x[i],
                k5.x[i],
                k6.x[i],
                k7.x[i],
            );
        }
        for j in 0..K {
            for i in 0..N {
                out.w[j][i] = comp(
                    self.y_old.w[j][i],
                    self.y.w[j][i],
                    k1.w[j][i],
                    k3.w[j][i],
                    k4.w[j][i],
                    k5.w[j][i],
                    k6.w[j][i],
                    k7.w[j][i],
                );
            }
        }
        out.trace_integral = comp(
            self.y_old.trace_integral,
            self.y.trace_integral,
            k1.trace_integral,
            k3.trace_integral,
            k4.trace_integral,
            k5.trace_integral,
            k6.trace_integral,
            k7.trace_integral,
        );
        Ok(())
    }

    fn eval(&mut self, eval: &mut StageEval<N, K>, t: f64, which: Which, into: usize) {
        let y = match which {
            Which::Y => &self.y,
            Which::Tmp => &self.tmp,
            Which::YNew => &self.y_new,
        };
        eval(t, y, &mut self.k[into]);
        self.evals += 1;
    }

    /// Weighted RMS norm of `v` with scales atol + rtol·max(|a|, |b|) over x (and the tangents
    /// when they are error-controlled).
    fn norm(&self, v: &VarState<N, K>, a: &VarState<N, K>, b: &VarState<N, K>) -> f64 {
        // x, then the tangents row by row: the slices' order.
        let len = if self.opts.tangent_error_control {
            N + N * K
        } else {
            N
        };
        weighted_rms(
            &v.as_slice()[..len],
            &a.as_slice()[..len],
            &b.as_slice()[..len],
            self.opts.rtol,
            self.opts.atol,
        )
    }

    /// Hairer's starting step: h ≈ (0.01 / ‖f″‖-estimate)^{1/5}, capped by h_max.
    fn initial_step(&mut self, eval: &mut StageEval<N, K>) -> f64 {
        let zero = VarState::ZERO;
        let d0 = self.norm(&self.y, &self.y, &zero);
        let d1 = self.norm(&self.k[0], &self.y, &zero);
        let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        h0 = h0.min(self.opts.h_max);
        let k0 = self.k[0];
        set_axpy(
            self.tmp.as_mut_slice(),
            self.y.as_slice(),
            h0,
            k0.as_slice(),
        );
        self.eval(eval, self.t + h0, Which::Tmp, 1);
        let mut diff = self.k[1];
        add_scaled(diff.as_mut_slice(), -1.0, k0.as_slice());
        let d2 = self.norm(&diff, &self.y, &zero) / h0;
        let dm = d1.max(d2);
        let h1 = if dm <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / dm).powf(0.2)
        };
        (100.0 * h0).min(h1).min(self.opts.h_max)
    }

    /// The seven stages and the trial solution `y_new` for step size `h`; returns the error norm.
    fn attempt(&mut self, eval: &mut StageEval<N, K>, h: f64) -> f64 {
        let t = self.t;
        self.stage_into_tmp(h, &[(A21, 0)]);
        self.eval(eval, t + C2 * h, Which::Tmp, 1);
        self.stage_into_tmp(h, &[(A31, 0), (A32, 1)]);
        self.eval(eval, t + C3 * h, Which::Tmp, 2);
        self.stage_into_tmp(h, &[(A41, 0), (A42, 1), (A43, 2)]);
        self.eval(eval, t + C4 * h, Which::Tmp, 3);
        self.stage_into_tmp(h, &[(A51, 0), (A52, 1), (A53, 2), (A54, 3)]);
        self.eval(eval, t + C5 * h, Which::Tmp, 4);
        self.stage_into_tmp(h, &[(A61, 0), (A62, 1), (A63, 2), (A64, 3), (A65, 4)]);
        self.eval(eval, t + h, Which::Tmp, 5);
        // 5th-order solution, then k7 = F(t + h, y_new) (reused as the next k1).
        self.stage_into_tmp(h, &[(A71, 0), (A73, 2), (A74, 3), (A75, 4), (A76, 5)]);
        self.y_new = self.tmp;
        self.eval(eval, t + h, Which::YNew, 6);
        // Error estimate into tmp.
        self.stage_err(h);
        let err = self.norm(&self.tmp, &self.y, &self.y_new);
        // A non-finite trial (in any part) must be rejected even if the norm skips that part.
        if self.y_new.non_finite_part().is_some() || self.k[6].non_finite_part().is_some() {
            f64::INFINITY
        } else {
            err
        }
    }

    /// `tmp = y + h Σ a_j k_j`.
    fn stage_into_tmp(&mut self, h: f64, terms: &[(f64, usize)]) {
        let (a0, j0) = terms[0];
        set_axpy(
            self.tmp.as_mut_slice(),
            self.y.as_slice(),
            h * a0,
            self.k[j0].as_slice(),
        );
        for &(a, j) in &terms[1..] {
            add_scaled(self.tmp.as_mut_slice(), h * a, self.k[j].as_slice());
        }
    }

    /// `tmp = h Σ E_j k_j` (the local error estimate).
    fn stage_err(&mut self, h: f64) {
        let zero = VarState::<N, K>::ZERO;
        let tmp = self.tmp.as_mut_slice();
        let [k1, _, k3, k4, k5, k6, k7] = &self.k;
        set_axpy(tmp, zero.as_slice(), h * E1, k1.as_slice());
        for (e, k) in [(E3, k3), (E4, k4), (E5, k5), (E6, k6), (E7, k7)] {
            add_scaled(tmp, h * e, k.as_slice());
        }
    }

    /// One step; see [`Stepper::step`]. Not inlined: one copy per `(N, K)`, whatever the field.
    #[inline(never)]
    fn step(&mut self, eval: &mut StageEval<N, K>) -> Result<StopReason, IntegrateError> {
        if self.k7_current {
            self.k[0] = self.k[6];
            self.k1_current = true;
            self.k7_current = false;
        }
        if !self.k1_current {
            self.eval(eval, self.t, Which::Y, 0);
            self.k1_current = true;
        }
        let opts = self.opts;
        let mut h = match self.h_next {
            Some(h) => h,
            None => self.initial_step(eval),
        }
        .min(opts.h_max);
        let expo1 = 0.2 - 0.75 * opts.beta;
        loop {
            let mut last = false;
            if let Some(ts) = self.t_stop {
                // Land on ts; stretch by up to 1 % rather than leave a sliver (as dopri5 does).
                if self.t + 1.01 * h >= ts {
                    h = ts - self.t;
                    last = true;
                }
            }
            let t_res = 16.0 * f64::EPSILON * self.t.abs().max(1e-300);
            if !(h >= opts.h_min && h > t_res) {
                return Err(IntegrateError::StepSizeUnderflow {
                    t: self.t,
                    h,
                    x: self.y.x.to_vec(),
                });
            }
            if self.steps + self.rejected >= opts.max_steps {
                return Err(IntegrateError::TooManySteps {
                    t: self.t,
                    h,
                    max_steps: opts.max_steps,
                    x: self.y.x.to_vec(),
                });
            }
            let err = self.attempt(eval, h);
            let fac11 = err.powf(expo1);
            if err <= 1.0 {
                // PI controller (Gustafsson; Hairer's dopri5 constants).
                let fac = (fac11 / self.err_old.powf(opts.beta) / opts.safety)
                    .clamp(1.0 / opts.fac_max, 1.0 / opts.fac_min);
                let mut h_new = h / fac;
                if self.last_rejected {
                    h_new = h_new.min(h);
                }
                self.err_old = err.max(1e-4);
                self.last_rejected = false;
                self.y_old = self.y;
                self.y = self.y_new;
                self.t_old = self.t;
                self.h_last = h;
                self.dense_valid = true;
                self.k1_current = false;
                self.k7_current = true;
                self.steps += 1;
                self.h_next = Some(h_new.min(opts.h_max));
                if last {
                    self.t = self.t_stop.take().unwrap_or(self.t + h);
                    return Ok(StopReason::StopTimeReached);
                }
                self.t += h;
                return Ok(StopReason::InternalStep);
            }
            // Rejected (err > 1 or NaN): shrink and retry.
            self.rejected += 1;
            self.last_rejected = true;
            let shrink = if err.is_finite() {
                (fac11 / opts.safety).min(1.0 / opts.fac_min)
            } else {
                1.0 / opts.fac_min
            };
            h /= shrink;
        }
    }
}

/// `out = y + c k`, on slices: one copy for every size, as a step's combinations are not
/// its hot part (the stages are).
#[inline(never)]
fn set_axpy(out: &mut [f64], y: &[f64], c: f64, k: &[f64]) {
    for ((out, y), k) in out.iter_mut().zip(y).zip(k) {
        *out = y + c * k;
    }
}

/// `out += c k`, on slices (see [`set_axpy`]).
#[inline(never)]
fn add_scaled(out: &mut [f64], c: f64, k: &[f64]) {
    for (out, k) in out.iter_mut().zip(k) {
        *out += c * k;
    }
}

/// √(mean of (v / (atol + rtol·max(|a|, |b|)))²): one copy for every (system, K) the
/// steppers are built for.
fn weighted_rms(v: &[f64], a: &[f64], b: &[f64], rtol: f64, atol: f64) -> f64 {
    let mut sum = 0.0;
    for ((v, a), b) in v.iter().zip(a).zip(b) {
        let s = atol + rtol * a.abs().max(b.abs());
        sum += (v / s) * (v / s);
    }
    (sum / v.len().max(1) as f64).sqrt()
}

/// Which buffer a stage is evaluated at.
#[derive(Clone, Copy)]
enum Which {
    Y,
    Tmp,
    YNew,
}

impl<F: VectorField<N>, const N: usize, const K: usize> Stepper<N, K> for Dopri5<F, N, K> {
    type Field = F;

    fn field(&self) -> &F {
        &self.field
    }

    fn t(&self) -> f64 {
        self.core.t
    }

    fn state(&self) -> &VarState<N, K> {
        &self.core.y
    }

    fn set_tangents(&mut self, w: &[[f64; N]; K]) {
        let core = &mut self.core;
        core.y.w = *w;
        core.k1_current = false;
        core.k7_current = false;
        core.dense_valid = false;
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), IntegrateError> {
        check_stop(self.core.t, t_stop)?;
        self.core.t_stop = Some(t_stop);
        Ok(())
    }

    fn step(&mut self) -> Result<StopReason, IntegrateError> {
        let (field, trace) = (&self.field, self.trace);
        self.core
            .step(&mut |t, y, dy| eval_stage(field, t, y, trace, dy))
    }

    fn steps(&self) -> u64 {
        self.core.steps
    }

    fn integrates_trace(&self) -> bool {
        self.trace
    }
}
