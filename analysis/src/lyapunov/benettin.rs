//! The Benettin–QR driver.
//!
//! Only the stepper is generic over the model: the loop over intervals sees it as a
//! `dyn` [`Driven`], so it is compiled once per `(N, K)`, and what each interval records and
//! everything after the loop — sorting, standard errors, the classification — is one
//! non-generic [`Measurement`] on slices, so the hundreds of (model, exponent count,
//! integrator) combinations the binary dispatches to share one copy of it.

use crate::integrate::{Dopri5, IntegrateError, Rk4, Stepper, VarState, VectorField};
use crate::progress::{Progress, Silent};

use super::classify::{classify, SignRule};
use super::result::{LyapunovResult, RunDetails, RunningEstimates};
use super::stats::{kaplan_yorke, stderr_of_batch_means};
use super::{
    initial_basis, orthonormalize, IntegratorChoice, IntervalEnds, LyapunovError, LyapunovSettings,
};

/// The most rows of running estimates a run keeps: longer runs record every ⌈K / this⌉-th
/// interval (and always the last), so memory stays bounded however many intervals are asked
/// for, while the convergence figure keeps far more points than it can show.
pub const MAX_RUNNING_ROWS: usize = 100_000;

/// The `K` largest Lyapunov exponents of ẋ = F(t, x) from `x0` at t = 0 (`K = N`: the full
/// spectrum), with the integrator, basis and horizon of `settings`.
///
/// `field` may be a reference (`&OpenLoop`, `&ClosedLoop`, …).
pub fn lyapunov_spectrum<F, const N: usize, const K: usize>(
    field: F,
    x0: &[f64; N],
    settings: &LyapunovSettings,
) -> Result<LyapunovResult, LyapunovError>
where
    F: VectorField<N>,
{
    lyapunov_spectrum_observed::<F, N, K>(field, x0, settings, &Silent)
}

/// [`lyapunov_spectrum`] reporting each interval to `progress`, and stopping with
/// [`LyapunovError::Interrupted`] when it is cancelled.
pub fn lyapunov_spectrum_observed<F, const N: usize, const K: usize>(
    field: F,
    x0: &[f64; N],
    settings: &LyapunovSettings,
    progress: &dyn Progress,
) -> Result<LyapunovResult, LyapunovError>
where
    F: VectorField<N>,
{
    settings.validate()?;
    check_count::<N, K>()?;
    let w0 = initial_basis::<N, K>(&settings.basis);
    let trace = settings.trace_check;
    match settings.integrator {
        IntegratorChoice::Rk4 { h } => drive(
            &mut Rk4::new(field, 0.0, *x0, w0, h, trace)?,
            settings,
            progress,
        ),
        IntegratorChoice::Dopri(opts) => drive(
            &mut Dopri5::new(field, 0.0, *x0, w0, opts, trace)?,
            settings,
            progress,
        ),
    }
}

/// The same with a stepper the caller built (any start time, integrator, initial tangents);
/// `settings.integrator` and `settings.basis` are then ignored, and `mean_trace` is reported
/// only if both `settings.trace_check` and the stepper's trace quadrature are on.
pub fn lyapunov_spectrum_with<S, const N: usize, const K: usize>(
    mut stepper: S,
    settings: &LyapunovSettings,
) -> Result<LyapunovResult, LyapunovError>
where
    S: Stepper<N, K>,
{
    drive(&mut stepper, settings, &Silent)
}

/// What the interval loop needs of a stepper, object-safe: the loop takes it as `dyn`, one
/// indirect call per interval, and is compiled once per `(N, K)` instead of once per stepper.
trait Driven<const N: usize, const K: usize> {
    fn t(&self) -> f64;
    fn state(&self) -> &VarState<N, K>;
    fn set_tangents(&mut self, w: &[[f64; N]; K]);
    fn advance_to(&mut self, t_end: f64) -> Result<(), IntegrateError>;
    fn steps(&self) -> u64;
    fn integrates_trace(&self) -> bool;
    /// The field's right-hand side at `(t, x)`.
    fn rhs(&self, t: f64, x: &[f64; N], out: &mut [f64; N]);
}

impl<S: Stepper<N, K>, const N: usize, const K: usize> Driven<N, K> for S {
    fn t(&self) -> f64 {
        Stepper::t(self)
    }
    fn state(&self) -> &VarState<N, K> {
        Stepper::state(self)
    }
    fn set_tangents(&mut self, w: &[[f64; N]; K]) {
        Stepper::set_tangents(self, w)
    }
    fn advance_to(&mut self, t_end: f64) -> Result<(), IntegrateError> {
        Stepper::advance_to(self, t_end)
    }
    fn steps(&self) -> u64 {
        Stepper::steps(self)
    }
    fn integrates_trace(&self) -> bool {
        Stepper::integrates_trace(self)
    }
    fn rhs(&self, t: f64, x: &[f64; N], out: &mut [f64; N]) {
        self.field().rhs(t, x, out)
    }
}

/// The transient and the measured intervals of one run: one copy per `(N, K)`.
#[inline(never)]
fn drive<const N: usize, const K: usize>(
    stepper: &mut dyn Driven<N, K>,
    settings: &LyapunovSettings,
    progress: &dyn Progress,
) -> Result<LyapunovResult, LyapunovError> {
    settings.validate()?;
    check_count::<N, K>()?;
    let t_sample = settings.t_sample;
    let trace = settings.trace_check && stepper.integrates_trace();

    // Transient: evolve state and basis, re-orthonormalise, forget the growth.
    let ends = IntervalEnds::new(
        stepper.t(),
        settings.transient,
        t_sample,
        settings.iterations,
    );
    progress.start(ends.intervals as u64, "intervals");
    let interval_done = || {
        progress.advance(1);
        if progress.cancelled() {
            Err(LyapunovError::Interrupted)
        } else {
            Ok(())
        }
    };
    for i in 1..=ends.n_transient {
        stepper.advance_to(ends.end(i))?;
        reorthonormalize(stepper)?;
        interval_done()?;
    }

    // Measurement: the log sums, the batch sums of the local exponents, and (decimated) the
    // running estimates; nothing grows with the number of intervals beyond those rows.
    let t0 = stepper.t();
    let mut measure = Measurement::new(
        K,
        settings,
        t0,
        trace.then_some(stepper.state().trace_integral),
    );
    let mut f = [0.0; N];
    for i in 1..=settings.iterations {
        let t_prev = stepper.t();
        stepper.advance_to(ends.end(ends.n_transient + i))?;
        let r = reorthonormalize(stepper)?;
        let (t, y) = (stepper.t(), stepper.state());
        stepper.rhs(t, &y.x, &mut f);
        measure.interval(i, &r, t_prev, t, y.trace_integral);
        measure.max_speed = measure.max_speed.max(norm(&f));
        measure.max_norm = measure.max_norm.max(norm(&y.x));
        interval_done()?;
    }
    let t_total = stepper.t() - t0;
    let y = stepper.state();
    let details = RunDetails {
        t_transient: t0 - ends.t_begin,
        t_sample,
        intervals: settings.iterations,
        steps: stepper.steps(),
        full_spectrum: K == N,
        at_equilibrium: false,
        max_speed: measure.max_speed,
        max_norm: measure.max_norm,
        final_time: stepper.t(),
        final_state: y.x.to_vec(),
    };
    Ok(measure.finish(t_total, y.trace_integral, K == N, settings, details))
}

/// The batches of the batch-means error: the last `count · size` of the `n` intervals cut into
/// `count` consecutive batches of `size`; leftover intervals at the start (the least converged
/// end) belong to none.
pub struct Batches {
    /// Number of batches.
    pub count: usize,
    /// Intervals per batch.
    pub size: usize,
    /// Leftover intervals at the start.
    pub first: usize,
}

impl Batches {
    /// The batches of `n` intervals into at most `count`.
    pub fn new(n: usize, count: usize) -> Self {
        let size = (n / count.max(1)).max(1);
        let count = count.min(n);
        Self {
            count,
            size,
            first: n - count * size,
        }
    }

    /// The batch of interval `i` (1-based).
    pub fn of(&self, i: usize) -> Option<usize> {
        (i > self.first).then(|| ((i - 1 - self.first) / self.size).min(self.count - 1))
    }
}

/// What the integration loop measures, interval by interval: not generic over the system, so
/// the hundreds of (model, exponent count, integrator) drivers share one copy of it.
struct Measurement {
    /// Σ log R_kk per tangent vector, in the stepper's order.
    log_sums: Vec<f64>,
    /// Batch sums of the local exponents, batch-major, `log_sums.len()` per batch.
    batch_sums: Vec<f64>,
    batches: Batches,
    running: RunningEstimates,
    /// Every `stride`-th interval (and the last) is a row of the running estimates.
    stride: usize,
    intervals: usize,
    record_running: bool,
    t0: f64,
    /// ∫ tr J at t0, when the trace is integrated and checked.
    q0: Option<f64>,
    /// The largest |f(x)| and |x| at the interval ends (an equilibrium has no speed).
    max_speed: f64,
    max_norm: f64,
}

impl Measurement {
    fn new(k: usize, settings: &LyapunovSettings, t0: f64, q0: Option<f64>) -> Self {
        let n = settings.iterations;
        let batches = Batches::new(n, settings.batches);
        let stride = n.div_ceil(MAX_RUNNING_ROWS).max(1);
        let mut running = RunningEstimates {
            k,
            ..RunningEstimates::default()
        };
        if settings.record_running {
            let rows = n.div_ceil(stride) + 1;
            running.t.reserve(rows);
            running.values.reserve(rows * k);
            running.sum.reserve(rows);
            running.mean_trace.reserve(rows);
        }
        Self {
            log_sums: vec![0.0; k],
            batch_sums: vec![0.0; batches.count * k],
            batches,
            running,
            stride,
            intervals: n,
            record_running: settings.record_running,
            t0,
            q0,
            max_speed: 0.0,
            max_norm: 0.0,
        }
    }

    /// Interval `i` (1-based) from `t_prev` to `t`: R's diagonal `r` and the trace integral at
    /// `t`.
    #[inline(never)]
    fn interval(&mut self, i: usize, r: &[f64], t_prev: f64, t: f64, q: f64) {
        let k = self.log_sums.len();
        let dt = t - t_prev;
        let batch = self.batches.of(i);
        for (j, (s, r)) in self.log_sums.iter_mut().zip(r).enumerate() {
            let lr = r.ln();
            *s += lr;
            if let Some(b) = batch {
                self.batch_sums[b * k + j] += lr / dt;
            }
        }
        if self.record_running && (i.is_multiple_of(self.stride) || i == self.intervals) {
            let elapsed = t - self.t0;
            let running = &mut self.running;
            running.t.push(elapsed);
            running
                .values
                .extend(self.log_sums.iter().map(|s| s / elapsed));
            running
                .sum
                .push(self.log_sums.iter().sum::<f64>() / elapsed);
            running
                .mean_trace
                .push(self.q0.map_or(f64::NAN, |q0| (q - q0) / elapsed));
        }
    }

    /// Sorts, estimates the errors and classifies: the end of every run.
    fn finish(
        self,
        t_total: f64,
        q: f64,
        full_spectrum: bool,
        settings: &LyapunovSettings,
        mut details: RunDetails,
    ) -> LyapunovResult {
        let k = self.log_sums.len();
        let batch_means: Vec<f64> = self
            .batch_sums
            .iter()
            .map(|s| s / self.batches.size as f64)
            .collect();
        let raw: Vec<f64> = self.log_sums.iter().map(|s| s / t_total).collect();
        // Sort descending and carry the order through every per-exponent series.
        let mut order: Vec<usize> = (0..k).collect();
        order.sort_by(|&a, &b| raw[b].total_cmp(&raw[a]));
        let exponents: Vec<f64> = order.iter().map(|&i| raw[i]).collect();
        let mut running = self.running;
        running.values = permute_rows(&running.values, &order);
        let stderr: Vec<f64> = order
            .iter()
            .map(|&i| {
                let column: Vec<f64> = batch_means.iter().skip(i).step_by(k).copied().collect();
                stderr_of_batch_means(&column)
            })
            .collect();
        let sum = exponents.iter().sum();
        let at_equilibrium = self.max_speed * t_total <= 1e-9 * self.max_norm.max(1.0);
        details.at_equilibrium = at_equilibrium;
        let rule = SignRule::from_settings(settings, t_total, &exponents);
        let (classification, signs) = classify(&exponents, &stderr, &rule, at_equilibrium);
        LyapunovResult {
            kaplan_yorke: kaplan_yorke(&exponents, full_spectrum),
            exponents,
            stderr,
            significance: settings.significance,
            zero_floor: rule.floor,
            signs,
            sum,
            mean_trace: self.q0.map(|q0| (q - q0) / t_total),
            classification,
            t_total,
            running,
            details,
        }
    }
}

/// Replaces the stepper's tangents by Q of their QR and returns R's (positive) diagonal.
fn reorthonormalize<const N: usize, const K: usize>(
    stepper: &mut dyn Driven<N, K>,
) -> Result<[f64; K], LyapunovError> {
    let mut w = stepper.state().w;
    let r = orthonormalize(&mut w);
    if let Some(index) = r.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(LyapunovError::Degenerate {
            t: stepper.t(),
            index,
            r: r[index],
        });
    }
    stepper.set_tangents(&w);
    Ok(r)
}

fn check_count<const N: usize, const K: usize>() -> Result<(), LyapunovError> {
    if K == 0 || K > N {
        return Err(LyapunovError::ExponentCount { k: K, n: N });
    }
    Ok(())
}

/// Reorders the columns of a row-major table with `order.len()` columns.
fn permute_rows(values: &[f64], order: &[usize]) -> Vec<f64> {
    values
        .chunks_exact(order.len())
        .flat_map(|row| order.iter().map(move |&k| row[k]))
        .collect()
}

fn norm<const N: usize>(v: &[f64; N]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}
