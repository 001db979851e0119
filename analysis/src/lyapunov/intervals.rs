//! When a Benettin run re-orthonormalises: the transient's interval ends, then the measured
//! ones, shared by `lyapunov_spectrum_with` and the maps' own driver (`sweep/lanes.rs`), which
//! must land on the very same times to keep its bits.

/// The interval ends of a run from `t_begin`: ⌈transient / T⌉ transient intervals of T (the
/// last one ending exactly at the transient's end t0), then the measured ones at t0 + k·T,
/// counted from t0 (not accumulated) so the horizon is exactly n·T.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct IntervalEnds {
    /// Where the run starts.
    pub(crate) t_begin: f64,
    t_sample: f64,
    /// The number of transient intervals.
    pub(crate) n_transient: usize,
    /// The end of the transient, where the averaging starts.
    pub(crate) t0: f64,
    /// Transient and measured intervals together.
    pub(crate) intervals: usize,
}

impl IntervalEnds {
    /// The ends of a run from `t_begin` with a transient of `transient`, intervals of
    /// `t_sample` and `iterations` measured intervals.
    pub(crate) fn new(t_begin: f64, transient: f64, t_sample: f64, iterations: usize) -> Self {
        let n_transient = (transient / t_sample * (1.0 - 1e-12)).ceil() as usize;
        Self {
            t_begin,
            t_sample,
            n_transient,
            t0: t_begin + transient,
            intervals: n_transient + iterations,
        }
    }

    /// The end of interval `i` (1-based).
    pub(crate) fn end(&self, i: usize) -> f64 {
        if i > self.n_transient {
            self.t0 + (i - self.n_transient) as f64 * self.t_sample
        } else if i == self.n_transient {
            self.t0
        } else {
            self.t_begin + i as f64 * self.t_sample
        }
    }

    /// Whether interval `i` is measured (after the transient).
    pub(crate) fn measured(&self, i: usize) -> bool {
        i > self.n_transient
    }

    /// The averaging horizon: the measured intervals' span.
    pub(crate) fn horizon(&self) -> f64 {
        self.end(self.intervals) - self.t0
    }
}
