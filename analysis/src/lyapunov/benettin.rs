//! The Benettin–QR driver.

use crate::integrate::{Dopri5, Rk4, Stepper, VectorField};

use super::classify::{classify, SignRule};
use super::result::{LyapunovResult, RunDetails, RunningEstimates};
use super::stats::{batch_means_stderr, kaplan_yorke};
use super::{initial_basis, orthonormalize, IntegratorChoice, LyapunovError, LyapunovSettings};

/// The `K` largest Lyapunov exponents of ẋ = F(t, x) from `x0` at t = 0 (`K = N`: the full
/// spectrum), with the integrator, basis and horizon of `settings`.
///
/// `field` may be a reference (`&OpenLoop`, `&ClosedLoop`, …). The CLI's runtime `--k` maps to
/// the const `K` by a `match` over 1..=N.
pub fn lyapunov_spectrum<F, const N: usize, const K: usize>(
    field: F,
    x0: &[f64; N],
    settings: &LyapunovSettings,
) -> Result<LyapunovResult, LyapunovError>
where
    F: VectorField<N>,
{
    settings.validate()?;
    check_count::<N, K>()?;
    let w0 = initial_basis::<N, K>(&settings.basis);
    let trace = settings.trace_check;
    match settings.integrator {
        IntegratorChoice::Rk4 { h } => {
            lyapunov_spectrum_with(Rk4::new(field, 0.0, *x0, w0, h, trace)?, settings)
        }
        IntegratorChoice::Dopri(opts) => {
            lyapunov_spectrum_with(Dopri5::new(field, 0.0, *x0, w0, opts, trace)?, settings)
        }
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
    settings.validate()?;
    check_count::<N, K>()?;
    let t_sample = settings.t_sample;
    let trace = settings.trace_check && stepper.integrates_trace();

    // Transient: evolve state and basis, re-orthonormalise, forget the growth.
    let t_begin = stepper.t();
    let n_transient = (settings.transient / t_sample * (1.0 - 1e-12)).ceil() as usize;
    for i in 1..=n_transient {
        let t_end = if i == n_transient {
            t_begin + settings.transient
        } else {
            t_begin + i as f64 * t_sample
        };
        stepper.advance_to(t_end)?;
        reorthonormalize(&mut stepper)?;
    }

    // Measurement.
    let t0 = stepper.t();
    let q0 = stepper.state().trace_integral;
    let n = settings.iterations;
    let mut log_sums = [0.0; K];
    let mut local = Vec::with_capacity(n * K);
    let mut running = RunningEstimates {
        k: K,
        ..RunningEstimates::default()
    };
    if settings.record_running {
        running.t.reserve(n);
        running.values.reserve(n * K);
        running.sum.reserve(n);
        running.mean_trace.reserve(n);
    }
    let (mut max_speed, mut max_norm) = (0.0f64, 0.0f64);
    let mut f = [0.0; N];
    for i in 1..=n {
        let t_prev = stepper.t();
        // From t0 (not accumulated) so the horizon is exactly n·T.
        stepper.advance_to(t0 + i as f64 * t_sample)?;
        let r = reorthonormalize(&mut stepper)?;
        let (t, y) = (stepper.t(), stepper.state());
        let dt = t - t_prev;
        for (s, r) in log_sums.iter_mut().zip(r.iter()) {
            let lr = r.ln();
            *s += lr;
            local.push(lr / dt);
        }
        stepper.field().rhs(t, &y.x, &mut f);
        max_speed = max_speed.max(norm(&f));
        max_norm = max_norm.max(norm(&y.x));
        if settings.record_running {
            let elapsed = t - t0;
            running.t.push(elapsed);
            running.values.extend(log_sums.iter().map(|s| s / elapsed));
            running.sum.push(log_sums.iter().sum::<f64>() / elapsed);
            running.mean_trace.push(if trace {
                (y.trace_integral - q0) / elapsed
            } else {
                f64::NAN
            });
        }
    }
    let t_total = stepper.t() - t0;
    let raw: Vec<f64> = log_sums.iter().map(|s| s / t_total).collect();

    // Sort descending and carry the order through every per-exponent series.
    let mut order: Vec<usize> = (0..K).collect();
    order.sort_by(|&a, &b| raw[b].total_cmp(&raw[a]));
    let exponents: Vec<f64> = order.iter().map(|&k| raw[k]).collect();
    let local = permute_rows(&local, &order);
    running.values = permute_rows(&running.values, &order);
    let stderr: Vec<f64> = (0..K)
        .map(|k| {
            let column: Vec<f64> = local.iter().skip(k).step_by(K).copied().collect();
            batch_means_stderr(&column, settings.batches)
        })
        .collect();

    let sum = exponents.iter().sum();
    let mean_trace = trace.then(|| (stepper.state().trace_integral - q0) / t_total);
    let at_equilibrium = max_speed * t_total <= 1e-9 * max_norm.max(1.0);
    let rule = SignRule {
        z: settings.significance,
        zero_band: settings.zero_band,
        convergence_tol: settings.convergence_tol,
        horizon: t_total,
    };
    let classification = classify(&exponents, &stderr, &rule, at_equilibrium);
    Ok(LyapunovResult {
        kaplan_yorke: kaplan_yorke(&exponents, K == N),
        exponents,
        stderr,
        sum,
        mean_trace,
        classification,
        t_total,
        running,
        details: RunDetails {
            t_transient: t0 - t_begin,
            t_sample,
            intervals: n,
            steps: stepper.steps(),
            full_spectrum: K == N,
            at_equilibrium,
            max_speed,
            max_norm,
            final_time: stepper.t(),
            final_state: stepper.state().x.to_vec(),
            local,
        },
    })
}

/// Replaces the stepper's tangents by Q of their QR and returns R's (positive) diagonal.
fn reorthonormalize<S, const N: usize, const K: usize>(
    stepper: &mut S,
) -> Result<[f64; K], LyapunovError>
where
    S: Stepper<N, K>,
{
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
