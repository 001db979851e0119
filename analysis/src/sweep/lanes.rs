//! The max-Lyapunov metric of many grid points, run eight at a time: the points' closed loops
//! are stepped together, their states kept as lane arrays ([`LaneStates`]), so the RK4
//! combinations, a plain PD law ([`LoopLanes`]) and the model's lanes kernel (one vector
//! instruction stream for eight points, see `twv_kernels::lanes`) are whole-lane operations,
//! while the rare work (interval ends, the settled tail) is done point by point with the code
//! of the one-point metric ([`max_lyapunov`], which is this driver with one lane). Every point
//! therefore gets the bits it has alone (`tests/tests/all/sweep_lanes.rs` checks it) and
//! depends only on its index.
//!
//! Each lane keeps its own clock and schedule, so a lane whose point has finished — it fell,
//! blew up, degenerated, reached the end of its horizon or came to rest (the settled tail,
//! [`super::settle`]) — takes the next point of the chunk at once instead of riding along
//! until the slowest of its group is done. A lane with nothing left to run is parked at a
//! finite start state (which keeps the lanes kernel on its fast path) and its results ignored.

use core::marker::PhantomData;
use std::sync::{Mutex, MutexGuard, PoisonError};

use twv_kernels::isa::{Calibration, Isa};
use twv_kernels::lanes::LANES;
use twv_model::Model;

use super::config::MetricSettings;
use super::metric::{lyapunov_settings, result};
use super::point::{PointResult, Status};
use super::settle::{at_rest, tail_log_growth};
use crate::control::{loop_states, LoopLanes, PidLoop};
use crate::integrate::{
    equal_steps, eval_stage, one_row, rk4_step_lanes, LaneField, LaneRk4Scratch, LaneStates,
    Projected, VarState,
};
use crate::lyapunov::{initial_basis, orthonormalize, InitialBasis, IntervalEnds};

/// λ1 of the closed loops `loops` (the grid points `indices`) from the model state `x0`, in
/// that order: exactly what [`max_lyapunov`] gives for each, eight at a time (fewer than eight
/// points run one by one), with the driver's build that `choice` picks.
pub fn max_lyapunov_lanes<M, const NX: usize, const NU: usize, const NA: usize>(
    loops: &[PidLoop<'_, M, NX, NU, NA>],
    x0: &[f64; NX],
    s: &MetricSettings,
    indices: &[usize],
    choice: &DriverChoice,
) -> Vec<PointResult>
where
    M: Model<NX, NU>,
{
    assert_eq!(loops.len(), indices.len(), "one grid index per loop");
    if loops.len() < LANES {
        return (loops.iter().zip(indices))
            .map(|(lp, &index)| max_lyapunov(lp, x0, s, index))
            .collect();
    }
    let first = core::array::from_fn(|l| loops[l]);
    drive(LoopLanes::new(first), loops, x0, s, indices, choice)
}

/// Which build of the maps' driver (per instruction set) runs a sweep's chunks: the fastest
/// on this CPU, found by timing its first chunks with each ([`Calibration`], as the RK4 steps
/// choose theirs; "the best instruction set" is not always the fastest). Shared by the threads
/// that run the chunks; every build gives the same bits, so the choice changes only the speed.
#[derive(Debug)]
pub struct DriverChoice {
    calibration: Mutex<Calibration>,
    /// Whether to time at all: a sweep of a few chunks would run a third of them on a slower
    /// build and learn nothing it could use.
    timed: bool,
}

impl Default for DriverChoice {
    /// The build of the instruction set the kernels use ([`twv_kernels::isa::current`]), untimed.
    fn default() -> Self {
        Self::with_timing(false)
    }
}

impl DriverChoice {
    /// A sweep's first chunks are timed when it has at least this many: the ≤ 9 timed ones
    /// (three rounds of up to three builds) are then at most a tenth of it.
    pub const MIN_TIMED_CHUNKS: usize = 90;

    /// The choice for a sweep of `chunks` chunks: timed when there are enough of them.
    pub fn for_chunks(chunks: usize) -> Self {
        Self::with_timing(chunks >= Self::MIN_TIMED_CHUNKS)
    }

    /// The choice by timing (`true`) or the kernels' instruction set (`false`).
    pub fn with_timing(timed: bool) -> Self {
        Self {
            calibration: Mutex::new(Calibration::NEW),
            timed,
        }
    }

    /// The build for the next chunk, and whether to time it.
    pub fn next(&self) -> (Isa, bool) {
        if self.timed {
            self.calibration().next()
        } else {
            (twv_kernels::isa::current(), false)
        }
    }

    /// Books a timed chunk of `isa` that took `per_step` seconds per step of its lanes.
    pub fn record(&self, isa: Isa, per_step: f64) {
        self.calibration().record(isa, per_step);
    }

    fn calibration(&self) -> MutexGuard<'_, Calibration> {
        // A thread that panicked while holding it left plain numbers: still usable.
        self.calibration
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }
}

/// λ1 of the closed loop's pitch-loop coordinates ([`loop_states`]: the tangent dynamics with
/// the drift directions projected off) from the model state `x0`: the Benettin run of
/// [`lyapunov_settings`] (RK4, one tangent vector from e₁, re-orthonormalised every T, averaged
/// after the transient), `Fell` as soon as |Φ| passes the fall angle (the run stops there), and
/// with `s.settle` the settled-tail shortcut ([`super::settle`]).
pub fn max_lyapunov<M, const NX: usize, const NU: usize, const NA: usize>(
    field: &PidLoop<'_, M, NX, NU, NA>,
    x0: &[f64; NX],
    s: &MetricSettings,
    index: usize,
) -> PointResult
where
    M: Model<NX, NU>,
{
    // One point is not worth timing builds for: the kernels' instruction set.
    let choice = DriverChoice::default();
    let mut one = drive(
        One(*field),
        core::slice::from_ref(field),
        x0,
        s,
        &[index],
        &choice,
    );
    one.remove(0)
}

/// `L` closed loops evaluated together, one per lane, each lane's loop replaceable.
trait LoopGroup<'a, M, const NX: usize, const NU: usize, const NA: usize, const L: usize> {
    /// Lane `lane` runs `lp` from now on.
    fn set(&mut self, lane: usize, lp: PidLoop<'a, M, NX, NU, NA>);
    /// The stage derivatives of every lane (`t[l]`, point `l` of `y` → point `l` of `dy`).
    fn eval(&mut self, t: &[f64; L], y: &LaneStates<NA, L>, dy: &mut LaneStates<NA, L>);
}

impl<'a, M, const NX: usize, const NU: usize, const NA: usize> LoopGroup<'a, M, NX, NU, NA, LANES>
    for LoopLanes<'a, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    fn set(&mut self, lane: usize, lp: PidLoop<'a, M, NX, NU, NA>) {
        LoopLanes::set(self, lane, lp);
    }

    #[inline(always)]
    fn eval(
        &mut self,
        t: &[f64; LANES],
        y: &LaneStates<NA, LANES>,
        dy: &mut LaneStates<NA, LANES>,
    ) {
        LoopLanes::eval(self, t, y, dy);
    }
}

/// One loop alone: the field's own evaluation (the one-point metric).
struct One<'a, M, const NX: usize, const NU: usize, const NA: usize>(PidLoop<'a, M, NX, NU, NA>);

impl<'a, M, const NX: usize, const NU: usize, const NA: usize> LoopGroup<'a, M, NX, NU, NA, 1>
    for One<'a, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    fn set(&mut self, _lane: usize, lp: PidLoop<'a, M, NX, NU, NA>) {
        self.0 = lp;
    }

    #[inline(always)]
    fn eval(&mut self, t: &[f64; 1], y: &LaneStates<NA, 1>, dy: &mut LaneStates<NA, 1>) {
        let mut d = VarState::ZERO;
        eval_stage(&self.0, t[0], &y.point(0), false, &mut d);
        dy.set_point(0, &d);
    }
}

/// The stage derivatives of the lanes' loops, each lane's tangent projected onto its point's
/// kept coordinates (`keep[i][l]`: all ones to keep, zero to drop; an idle lane keeps all).
struct LaneStages<'g, 'a, G, M, const NX: usize, const NU: usize, const NA: usize, const L: usize> {
    group: &'g mut G,
    keep: &'g [[u64; L]; NA],
    loops: PhantomData<PidLoop<'a, M, NX, NU, NA>>,
}

impl<'a, G, M, const NX: usize, const NU: usize, const NA: usize, const L: usize> LaneField<NA, L>
    for LaneStages<'_, 'a, G, M, NX, NU, NA, L>
where
    G: LoopGroup<'a, M, NX, NU, NA, L>,
    M: Model<NX, NU>,
{
    #[inline(always)]
    fn eval(&mut self, t: &[f64; L], y: &LaneStates<NA, L>, dy: &mut LaneStates<NA, L>) {
        self.group.eval(t, y, dy);
        // `project` lane by lane: a dropped coordinate becomes +0 (its bits ANDed with zero),
        // a kept one is unchanged (with all ones), one vector AND per row.
        for (w, keep) in dy.w.iter_mut().zip(self.keep) {
            let w = one_row(w);
            let mut row = *w;
            for l in 0..L {
                row[l] = f64::from_bits(row[l].to_bits() & keep[l]);
            }
            *w = row;
        }
    }
}

/// The projection's masks of a kept and of a dropped coordinate ([`LaneStages`]).
const KEEP: u64 = u64::MAX;
const DROP: u64 = 0;

/// How a point's run ended: its status, λ1 and when it came to rest.
struct End {
    status: Status,
    value: Option<f64>,
    settled_at: Option<f64>,
}

impl End {
    fn without_value(status: Status) -> Self {
        Self {
            status,
            value: None,
            settled_at: None,
        }
    }
}

/// One point's run: where it is in its schedule and what it has measured so far.
#[derive(Clone, Copy)]
struct Run<const NA: usize> {
    /// The point's position in the chunk.
    point: usize,
    start: VarState<NA, 1>,
    keep: [bool; NA],
    /// The current interval (1-based), its end, its steps still to take and their size.
    interval: usize,
    t_stop: f64,
    steps_left: u64,
    h: f64,
    t: f64,
    log_sum: f64,
}

impl<const NA: usize> Run<NA> {
    /// The run of point `point` (loop `lp`) from `x0`, or how it ends before its first step:
    /// an invalid step or a non-finite start blows up, invalid settings (`settings_ok` false,
    /// the drive's one check of `lyapunov_settings(s)`) fail, as in the Benettin driver.
    fn start<M, const NX: usize, const NU: usize>(
        lp: &PidLoop<'_, M, NX, NU, NA>,
        x0: &[f64; NX],
        (s, settings_ok): (&MetricSettings, bool),
        ends: &IntervalEnds,
        point: usize,
    ) -> Result<Self, Status>
    where
        M: Model<NX, NU>,
    {
        let start = VarState::new(lp.initial_state(x0), initial_basis(&InitialBasis::Identity));
        if !(s.h.is_finite() && s.h > 0.0) || start.non_finite_part().is_some() {
            return Err(Status::BlewUp);
        }
        if !settings_ok {
            return Err(Status::Failed);
        }
        let mut run = Self {
            point,
            start,
            keep: loop_states(lp, &[start.x]),
            interval: 0,
            t_stop: 0.0,
            steps_left: 0,
            h: s.h,
            t: 0.0,
            log_sum: 0.0,
        };
        run.next_interval(s, ends);
        Ok(run)
    }

    fn next_interval(&mut self, s: &MetricSettings, ends: &IntervalEnds) {
        self.interval += 1;
        self.t_stop = ends.end(self.interval);
        (self.steps_left, self.h) = equal_steps(self.t_stop - self.t, s.h);
    }

    /// Books the step just taken to point `l` of `y` (`finite`: whether it is); `Some` when
    /// the run ended.
    #[inline(always)]
    fn after_step<M, const NX: usize, const NU: usize, const L: usize>(
        &mut self,
        (y, l): (&mut LaneStates<NA, L>, usize),
        finite: bool,
        lp: &PidLoop<'_, M, NX, NU, NA>,
        s: &MetricSettings,
        ends: &IntervalEnds,
    ) -> Option<End>
    where
        M: Model<NX, NU>,
    {
        if !finite {
            return Some(End::without_value(Status::BlewUp));
        }
        if y.x[lp.plant().measured.phi][l].abs() > s.fall_angle {
            return Some(End::without_value(Status::Fell));
        }
        self.steps_left -= 1;
        if self.steps_left > 0 {
            self.t += self.h;
            return None;
        }
        self.t = self.t_stop;
        let mut point = y.point(l);
        let end = self.interval_end(&mut point, lp, s, ends);
        y.set_tangent(l, &point.w[0]);
        end
    }

    /// Re-orthonormalises at an interval end, adds a measured interval's growth, and ends the
    /// run at the horizon or when the loop has come to rest.
    #[cold]
    fn interval_end<M, const NX: usize, const NU: usize>(
        &mut self,
        y: &mut VarState<NA, 1>,
        lp: &PidLoop<'_, M, NX, NU, NA>,
        s: &MetricSettings,
        ends: &IntervalEnds,
    ) -> Option<End>
    where
        M: Model<NX, NU>,
    {
        let r = orthonormalize(&mut y.w)[0];
        if !(r.is_finite() && r > 0.0) {
            return Some(End::without_value(Status::Failed));
        }
        if ends.measured(self.interval) {
            let growth = r.ln();
            self.log_sum += growth;
            let done = |log_sum: f64, settled_at| End {
                status: Status::Ok,
                value: Some(log_sum / ends.horizon()),
                settled_at,
            };
            if self.interval == ends.intervals {
                return Some(done(self.log_sum, None));
            }
            if let Some(tail) = self.settled_tail(y, lp, s, ends, growth / s.t_sample) {
                return Some(done(self.log_sum + tail, Some(self.t)));
            }
        }
        self.next_interval(s, ends);
        None
    }

    /// Σ ln R of the rest of the horizon when the loop is at rest (`rate`: this interval's
    /// local exponent) and the shortcut is on.
    fn settled_tail<M, const NX: usize, const NU: usize>(
        &self,
        y: &VarState<NA, 1>,
        lp: &PidLoop<'_, M, NX, NU, NA>,
        s: &MetricSettings,
        ends: &IntervalEnds,
        rate: f64,
    ) -> Option<f64>
    where
        M: Model<NX, NU>,
    {
        let distance = s.settle_distance?;
        let field = Projected {
            field: lp,
            keep: self.keep,
        };
        if !at_rest(&field, self.t, &y.x, rate, distance) {
            return None;
        }
        let steps = (self.interval + 1..=ends.intervals)
            .map(|i| equal_steps(ends.end(i) - ends.end(i - 1), s.h).0)
            .sum();
        let h = equal_steps(s.t_sample, s.h).1;
        tail_log_growth(&field, self.t, &y.x, &y.w[0], h, steps)
    }
}

/// Runs every loop of `loops` through the `L` lanes of `group` (whose lanes may hold any loops
/// of the same model to begin with), refilling a lane as soon as its point is done; with the
/// build of [`drive_inline`] that `choice` picks.
fn drive<'a, G, M, const NX: usize, const NU: usize, const NA: usize, const L: usize>(
    group: G,
    loops: &[PidLoop<'a, M, NX, NU, NA>],
    x0: &[f64; NX],
    s: &MetricSettings,
    indices: &[usize],
    choice: &DriverChoice,
) -> Vec<PointResult>
where
    G: LoopGroup<'a, M, NX, NU, NA, L>,
    M: Model<NX, NU>,
{
    // For a model that evaluates an IR the builds per instruction set are never instantiated
    // (a constant per model type, `Model::COMPILED_IN`).
    #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
    if M::COMPILED_IN {
        let (isa, timed) = choice.next();
        let start = timed.then(std::time::Instant::now);
        let (results, steps) = match isa {
            // SAFETY: `current` and `Calibration::next` give AVX-512 only when the CPU and the
            // OS support AVX-512F and AVX-512VL.
            Isa::Avx512 => unsafe { drive_avx512(group, loops, x0, s, indices) },
            // SAFETY: they give AVX2 only when the CPU and the OS support it.
            Isa::Avx2 => unsafe { drive_avx2(group, loops, x0, s, indices) },
            Isa::Neon | Isa::Baseline => drive_inline(group, loops, x0, s, indices),
        };
        if let Some(start) = start {
            choice.record(isa, start.elapsed().as_secs_f64() / steps.max(1) as f64);
        }
        return results;
    }
    #[cfg(not(all(target_arch = "x86_64", not(debug_assertions))))]
    let _ = choice;
    drive_inline(group, loops, x0, s, indices).0
}

/// A build of [`drive_inline`] for the instruction sets `$features`, which the CPU must have.
macro_rules! drive_build {
    ($(#[$doc:meta])* $name:ident, $features:literal) => {
        $(#[$doc])*
        ///
        /// # Safety
        #[doc = concat!("The CPU must have ", $features, ".")]
        #[cfg(all(target_arch = "x86_64", not(debug_assertions)))]
        #[target_feature(enable = $features)]
        unsafe fn $name<'a, G, M, const NX: usize, const NU: usize, const NA: usize, const L: usize>(
            group: G,
            loops: &[PidLoop<'a, M, NX, NU, NA>],
            x0: &[f64; NX],
            s: &MetricSettings,
            indices: &[usize],
        ) -> (Vec<PointResult>, u64)
        where
            G: LoopGroup<'a, M, NX, NU, NA, L>,
            M: Model<NX, NU>,
        {
            drive_inline(group, loops, x0, s, indices)
        }
    };
}

drive_build!(
    /// [`drive_inline`] built for AVX-512: the laws, the RK4 combinations and the assembly of
    /// the loops' derivatives become 8-wide operations, and the lanes kernel is called within
    /// the same build. The same IEEE operations in the same order as the baseline build (Rust
    /// never fuses a multiply and an add), so the same bits; release builds only, as the RK4
    /// steps'.
    drive_avx512,
    "avx512f,avx512vl"
);
drive_build!(
    /// The same for AVX2 (4-wide).
    drive_avx2,
    "avx2"
);

/// [`drive`] written out, every step inlined: the body of its builds. Returns the results and
/// the number of steps the lanes took together.
#[inline(always)]
fn drive_inline<'a, G, M, const NX: usize, const NU: usize, const NA: usize, const L: usize>(
    mut group: G,
    loops: &[PidLoop<'a, M, NX, NU, NA>],
    x0: &[f64; NX],
    s: &MetricSettings,
    indices: &[usize],
) -> (Vec<PointResult>, u64)
where
    G: LoopGroup<'a, M, NX, NU, NA, L>,
    M: Model<NX, NU>,
{
    let ends = IntervalEnds::new(0.0, s.transient, s.t_sample, s.iterations);
    let settings_ok = lyapunov_settings(s).validate().is_ok();
    let mut results: Vec<Option<PointResult>> = vec![None; loops.len()];
    let finish = |results: &mut Vec<Option<PointResult>>, point: usize, end: End| {
        let g = loops[point].settings().pitch.gains;
        let mut r = result(indices[point], &g, end.value, end.status);
        r.settled_at = end.settled_at.filter(|_| r.status == Status::Ok);
        results[point] = Some(r);
    };
    let mut runs: [Option<Run<NA>>; L] = [None; L];
    let mut y = LaneStates::<NA, L>::ZERO;
    // What an idle lane is reset to after every step: the start of the last point it ran.
    let mut parked = [VarState::<NA, 1>::ZERO; L];
    // Each lane's projection (an idle lane keeps every coordinate), time and step size.
    let mut keep = [[KEEP; L]; NA];
    let (mut t, mut h) = ([0.0; L], [s.h; L]);
    let mut scratch = LaneRk4Scratch::<NA, L>::ZERO;
    let mut next = 0;
    let mut steps = 0;
    loop {
        // Idle lanes take the next points; a point that ends before its first step is booked.
        for l in 0..L {
            while runs[l].is_none() && next < loops.len() {
                let point = next;
                next += 1;
                match Run::start(&loops[point], x0, (s, settings_ok), &ends, point) {
                    Ok(run) => {
                        group.set(l, loops[point]);
                        y.set_point(l, &run.start);
                        parked[l] = run.start;
                        for (row, k) in keep.iter_mut().zip(run.keep) {
                            row[l] = if k { KEEP } else { DROP };
                        }
                        (t[l], h[l]) = (run.t, run.h);
                        runs[l] = Some(run);
                    }
                    Err(status) => finish(&mut results, point, End::without_value(status)),
                }
            }
        }
        if runs.iter().all(Option::is_none) {
            break;
        }
        let mut stages = LaneStages {
            group: &mut group,
            keep: &keep,
            loops: PhantomData,
        };
        let finite = rk4_step_lanes(&t, &h, &mut y, &mut scratch, &mut stages);
        steps += 1;
        for l in 0..L {
            let Some(run) = &mut runs[l] else {
                y.set_point(l, &parked[l]);
                continue;
            };
            let point = run.point;
            if let Some(end) = run.after_step((&mut y, l), finite[l], &loops[point], s, &ends) {
                finish(&mut results, point, end);
                runs[l] = None;
                y.set_point(l, &parked[l]);
                for row in &mut keep {
                    row[l] = KEEP;
                }
                (t[l], h[l]) = (0.0, s.h);
            } else {
                (t[l], h[l]) = (run.t, run.h);
            }
        }
    }
    (results.into_iter().flatten().collect(), steps)
}
