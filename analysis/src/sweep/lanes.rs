//! The max-Lyapunov metric at [`LANES`] grid points at once: the points' closed loops are
//! stepped together so the model runs through its lanes kernel (one AVX-512 instruction stream
//! for eight points, see `twv_kernels::lanes`) and a plain PD law as lane arrays
//! ([`LoopLanes`]), while everything else is done point by point with the very code of the
//! one-point path ([`rk4_step_each`], [`orthonormalize`]). Every point therefore gets the bits
//! of [`metric::max_lyapunov`](super::metric::max_lyapunov) (`tests/tests/all/sweep_lanes.rs`
//! checks it) and still depends only on its index.
//!
//! The points share the time grid (same h, T and horizon), so one clock drives them all. A
//! point that falls, blows up or degenerates is finished with that status and from then on put
//! back to its start state after every step (its results are ignored; a finite state near the
//! start keeps the lanes kernel on its fast path); the group stops when every point is finished.

use twv_kernels::lanes::LANES;
use twv_model::Model;

use super::config::MetricSettings;
use super::metric::{lyapunov_settings, max_lyapunov, result};
use super::point::{PointResult, Status};
use crate::control::{loop_states, LoopLanes, PidLoop};
use crate::integrate::{equal_steps, project, rk4_step_each, Rk4Scratch, VarState};
use crate::lyapunov::{initial_basis, orthonormalize};

/// λ1 of the closed loops `loops[l]` (the grid points `indices[l]`) from the model state `x0`:
/// exactly what [`max_lyapunov`] gives for each, computed eight at a time.
pub fn max_lyapunov_lanes<M, const NX: usize, const NU: usize, const NA: usize>(
    loops: &[PidLoop<'_, M, NX, NU, NA>; LANES],
    x0: &[f64; NX],
    s: &MetricSettings,
    indices: [usize; LANES],
) -> [PointResult; LANES]
where
    M: Model<NX, NU>,
{
    let settings = lyapunov_settings(s);
    let start: [VarState<NA, 1>; LANES] = core::array::from_fn(|l| {
        VarState::new(loops[l].initial_state(x0), initial_basis(&settings.basis))
    });
    // What the one-point path reports as an error before its first step (invalid settings or
    // step, a non-finite start) is left to it.
    let plain = settings.validate().is_err()
        || !(s.h.is_finite() && s.h > 0.0)
        || start.iter().any(|y| y.non_finite_part().is_some());
    if plain {
        return core::array::from_fn(|l| max_lyapunov(&loops[l], x0, s, indices[l]));
    }
    let keep: [[bool; NA]; LANES] = core::array::from_fn(|l| loop_states(&loops[l], &[start[l].x]));

    let phi = loops[0].plant().measured.phi;
    let field = LoopLanes::new(loops);
    let mut y = start;
    let mut scratch = Rk4Scratch::<NA, 1, LANES>::ZERO;
    let mut finished: [Option<Status>; LANES] = [None; LANES];
    let mut log_sum = [0.0; LANES];
    let mut t = 0.0;
    // The interval ends of `lyapunov_spectrum_with`: the transient's, then K measured ones
    // counted from its end, each reached in equal steps of about h.
    let n_transient = (settings.transient / settings.t_sample * (1.0 - 1e-12)).ceil() as usize;
    let t0 = settings.transient;
    let ends = (1..=n_transient)
        .map(|i| {
            let end = if i == n_transient {
                settings.transient
            } else {
                i as f64 * settings.t_sample
            };
            (end, false)
        })
        .chain((1..=settings.iterations).map(|i| (t0 + i as f64 * settings.t_sample, true)));
    'intervals: for (t_stop, measured) in ends {
        let (steps, h) = equal_steps(t_stop - t, s.h);
        for step in 1..=steps {
            let finite = rk4_step_each(t, h, &mut y, &mut scratch, |t, y, dy| {
                field.eval(t, y, dy);
                for (d, k) in dy.iter_mut().zip(&keep) {
                    project(k, &mut d.w[0]);
                }
            });
            t = if step == steps { t_stop } else { t + h };
            for l in 0..LANES {
                if finished[l].is_none() {
                    if !finite[l] {
                        finished[l] = Some(Status::BlewUp);
                    } else if y[l].x[phi].abs() > s.fall_angle {
                        finished[l] = Some(Status::Fell);
                    }
                }
                if finished[l].is_some() {
                    y[l] = start[l];
                }
            }
            if finished.iter().all(Option::is_some) {
                break 'intervals;
            }
        }
        for l in 0..LANES {
            if finished[l].is_some() {
                continue;
            }
            let r = orthonormalize(&mut y[l].w)[0];
            if !(r.is_finite() && r > 0.0) {
                finished[l] = Some(Status::Failed);
            } else if measured {
                log_sum[l] += r.ln();
            }
        }
    }
    core::array::from_fn(|l| {
        let g = loops[l].settings().pitch.gains;
        match finished[l] {
            Some(status) => result(indices[l], &g, None, status),
            None => result(indices[l], &g, Some(log_sum[l] / (t - t0)), Status::Ok),
        }
    })
}
