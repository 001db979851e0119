//! The classical fourth-order Runge–Kutta method with a fixed step (the study's integrator).

use super::state::eval_stage;
use super::stepper::{check_initial, check_stop};
use super::{BlowUpPart, IntegrateError, Stepper, StopReason, VarState, VectorField};

/// Fixed-step RK4 on the variational system.
///
/// Steps have the nominal size `h`; when a stop time is set, the interval to it is divided
/// into ⌈(t_stop − t)/h⌉ equal steps so the last one lands exactly on it (with T = 0.1 and
/// h = 10⁻³ every step is h). Since RK4 is linear in the tangents and x does not depend on them,
/// re-orthonormalising between steps does not change the step sequence: finite-time spectra are
/// invariant to the re-orthonormalisation interval up to round-off.
#[derive(Debug, Clone)]
pub struct Rk4<F, const N: usize, const K: usize> {
    field: F,
    t: f64,
    h: f64,
    t_stop: Option<f64>,
    /// Steps left to the stop time and their common size (set by `set_stop_time`).
    stop_steps: u64,
    stop_h: f64,
    trace: bool,
    steps: u64,
    y: VarState<N, K>,
    scratch: Rk4Scratch<N, K>,
    /// Which build of the steps `advance_to` runs (timed on its first calls; the builds exist
    /// in release builds only).
    #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
    calibration: twv_kernels::isa::Calibration,
}

impl<F: VectorField<N>, const N: usize, const K: usize> Rk4<F, N, K> {
    /// A stepper at `(t0, x0, w0)` with step `h`; `trace` turns on the ∫ tr J quadrature.
    pub fn new(
        field: F,
        t0: f64,
        x0: [f64; N],
        w0: [[f64; N]; K],
        h: f64,
        trace: bool,
    ) -> Result<Self, IntegrateError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(IntegrateError::InvalidStepSize { h });
        }
        let y = VarState::new(x0, w0);
        check_initial(t0, &y)?;
        Ok(Self {
            field,
            t: t0,
            h,
            t_stop: None,
            stop_steps: 0,
            stop_h: h,
            trace,
            steps: 0,
            y,
            scratch: Rk4Scratch::ZERO,
            #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
            calibration: twv_kernels::isa::Calibration::NEW,
        })
    }

    /// The nominal step size.
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// [`Stepper::advance_to`] written out, every step inlined: the body of the builds below.
    #[inline(always)]
    fn advance_to_inline(&mut self, t_end: f64) -> Result<(), IntegrateError> {
        if t_end == self.t {
            return Ok(());
        }
        self.set_stop_time(t_end)?;
        while self.step()? != StopReason::StopTimeReached {}
        Ok(())
    }

    /// The steps built for AVX-512: the RK4 combinations of the state and its tangents (9 × 8
    /// doubles for the vehicle's full spectrum) become 8-wide operations. The same IEEE
    /// operations in the same order as the baseline build (Rust never fuses a multiply and an
    /// add), so the same bits; only release builds carry it (tests build at opt-level 1, where
    /// it would buy nothing and cost compile time).
    ///
    /// # Safety
    /// The CPU must have AVX-512F and AVX-512VL.
    #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
    #[target_feature(enable = "avx512f,avx512vl")]
    unsafe fn advance_to_avx512(&mut self, t_end: f64) -> Result<(), IntegrateError> {
        self.advance_to_inline(t_end)
    }

    /// The same for AVX2 (4-wide).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
    #[target_feature(enable = "avx2")]
    unsafe fn advance_to_avx2(&mut self, t_end: f64) -> Result<(), IntegrateError> {
        self.advance_to_inline(t_end)
    }

    /// One RK4 step of size `h` from the current point, in four fused passes over the state;
    /// returns whether the new point is finite. Per point the operations of `rk4_step_lanes`
    /// (the maps' lane arrays), so a point has the same bits in either form.
    ///
    /// The stages are one loop, so the field's evaluation (the model's kernel, inlined) is
    /// compiled once per build of the steps rather than four times: written out stage by stage
    /// each build was tens of kilobytes of machine code, more than the CPU's instruction cache,
    /// and the largest part of the analysis crate's compile time.
    #[inline(always)]
    fn rk4_step(&mut self, h: f64) -> bool {
        let (field, trace, t) = (&self.field, self.trace, self.t);
        let Rk4Scratch { k, acc, tmp } = &mut self.scratch;
        let y = &mut self.y;
        let half = 0.5 * h;
        let (t_half, t_end) = (t + half, t + h);
        let times = [t, t_half, t_half, t_end];
        // The step to the next stage's point: y + half k, y + half k, y + h k.
        let to_next = [half, half, h];
        for stage in 0..4 {
            let at = if stage == 0 { &*y } else { &*tmp };
            eval_stage(field, times[stage], at, trace, k);
            if stage == 3 {
                break;
            }
            // acc = k, then acc += 2 k; the next stage's point tmp = y + c k.
            let (c, first) = (to_next[stage], stage == 0);
            acc.zip_pair(tmp, y, k, |a, s, y, k| {
                *a = if first { k } else { *a + 2.0 * k };
                *s = y + c * k;
            });
        }
        y.add_sum_checked(h / 6.0, acc, k)
    }
}

/// The stage derivatives, running sum and stage points of one RK4 step.
#[derive(Debug, Clone)]
struct Rk4Scratch<const N: usize, const K: usize> {
    k: VarState<N, K>,
    acc: VarState<N, K>,
    tmp: VarState<N, K>,
}

impl<const N: usize, const K: usize> Rk4Scratch<N, K> {
    const ZERO: Self = Self {
        k: VarState::ZERO,
        acc: VarState::ZERO,
        tmp: VarState::ZERO,
    };
}

/// The equal steps to a stop time (shared with the export runtime's and firmware's RK4).
pub(crate) use twv_step::equal_steps;

impl<F: VectorField<N>, const N: usize, const K: usize> Stepper<N, K> for Rk4<F, N, K> {
    type Field = F;

    fn field(&self) -> &F {
        &self.field
    }

    fn t(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &VarState<N, K> {
        &self.y
    }

    fn set_tangents(&mut self, w: &[[f64; N]; K]) {
        self.y.w = *w;
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), IntegrateError> {
        check_stop(self.t, t_stop)?;
        // Equal steps that land on t_stop.
        (self.stop_steps, self.stop_h) = equal_steps(t_stop - self.t, self.h);
        self.t_stop = Some(t_stop);
        Ok(())
    }

    fn advance_to(&mut self, t_end: f64) -> Result<(), IntegrateError> {
        // A constant per field type: for a field that evaluates an IR the builds per
        // instruction set are never instantiated (`VectorField::COMPILED_IN`).
        #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
        if F::COMPILED_IN {
            use twv_kernels::isa::Isa;
            let (isa, timed) = self.calibration.next();
            let (start, steps) = (timed.then(std::time::Instant::now), self.steps);
            let done = match isa {
                // SAFETY: `Calibration::next` offers AVX-512 only when `isa::current()` is
                // AVX-512, i.e. the CPU and the OS support AVX-512F and AVX-512VL.
                Isa::Avx512 => unsafe { self.advance_to_avx512(t_end) },
                // SAFETY: offered only when `isa::current()` is at least AVX2.
                Isa::Avx2 => unsafe { self.advance_to_avx2(t_end) },
                // (NEON builds only the lanes kernel: `Calibration` never offers it for steps.)
                Isa::Neon | Isa::Baseline => self.advance_to_inline(t_end),
            };
            if let Some(start) = start {
                let steps = (self.steps - steps).max(1) as f64;
                self.calibration
                    .record(isa, start.elapsed().as_secs_f64() / steps);
            }
            return done;
        }
        self.advance_to_inline(t_end)
    }

    #[inline(always)]
    fn step(&mut self) -> Result<StopReason, IntegrateError> {
        let (h, last) = match self.t_stop {
            Some(_) => (self.stop_h, self.stop_steps == 1),
            None => (self.h, false),
        };
        // Only x is kept for the error report: copying the whole variational state every step
        // would cost more than the check. After an error the stepper is not to be stepped on.
        let x0 = self.y.x;
        if !self.rk4_step(h) {
            return Err(IntegrateError::BlowUp {
                part: self.y.non_finite_part().unwrap_or(BlowUpPart::State),
                t: self.t,
                h,
                x: x0.to_vec(),
            });
        }
        self.steps += 1;
        self.stop_steps = self.stop_steps.saturating_sub(1);
        if last {
            self.t = self.t_stop.take().unwrap_or(self.t + h);
            Ok(StopReason::StopTimeReached)
        } else {
            self.t += h;
            Ok(StopReason::InternalStep)
        }
    }

    fn steps(&self) -> u64 {
        self.steps
    }

    fn integrates_trace(&self) -> bool {
        self.trace
    }
}
