//! The result of a run: the summary that serialises to the `--json` form, the running
//! estimates (CSV), and run details.

use std::io::{self, Write};

use serde::Serialize;

use super::Classification;

/// A Lyapunov spectrum with its diagnostics.
///
/// Serialises (serde) to exactly the `twv lyap --json` object
/// `{"exponents", "stderr", "sum", "mean_trace", "kaplan_yorke", "classification", "t_total"}`;
/// the running estimates and run details are kept out of it and written separately
/// ([`RunningEstimates::write_csv`]).
#[derive(Debug, Clone, Serialize)]
pub struct LyapunovResult {
    /// The exponents λ_1 ≥ … ≥ λ_K (1/s).
    pub exponents: Vec<f64>,
    /// Batch-means standard error of each exponent (same order).
    pub stderr: Vec<f64>,
    /// Σλ.
    pub sum: f64,
    /// Time average of tr(∂f/∂x) over the same horizon and trajectory (`None` if the trace
    /// check was off). Equals `sum` up to integration error when K = N; for K < N it bounds
    /// the missing exponents' sum: Σ_{k>K} λ_k = mean_trace − sum.
    pub mean_trace: Option<f64>,
    /// Kaplan–Yorke dimension (`None` when a partial spectrum cannot determine it).
    pub kaplan_yorke: Option<f64>,
    /// The verdict, serialised as its description.
    pub classification: Classification,
    /// The averaging horizon T·K (s) the exponents are time averages over (the transient is
    /// not included; it is in [`RunDetails::t_transient`]).
    pub t_total: f64,
    /// Running estimates at every re-orthonormalisation.
    #[serde(skip)]
    pub running: RunningEstimates,
    /// How the run went.
    #[serde(skip)]
    pub details: RunDetails,
}

impl LyapunovResult {
    /// |Σλ − ⟨tr J⟩| relative to max(max|λ|, 1/t_total): the identity check for a full spectrum
    /// (`None` without the trace quadrature).
    pub fn trace_residual(&self) -> Option<f64> {
        let scale = self
            .exponents
            .iter()
            .fold(1.0 / self.t_total, |m, l| m.max(l.abs()));
        self.mean_trace.map(|m| (self.sum - m).abs() / scale)
    }
}

/// Details of a run that are not part of the summary.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunDetails {
    /// Discarded transient (s).
    pub t_transient: f64,
    /// Re-orthonormalisation interval (s).
    pub t_sample: f64,
    /// Number of intervals averaged.
    pub intervals: usize,
    /// Accepted integrator steps (transient included).
    pub steps: u64,
    /// Whether all N exponents were computed.
    pub full_spectrum: bool,
    /// Whether the orbit stayed on an equilibrium (moved less than 10⁻⁹ relative over the
    /// horizon).
    pub at_equilibrium: bool,
    /// Largest ‖ẋ‖ at the re-orthonormalisation times.
    pub max_speed: f64,
    /// Largest ‖x‖ at the re-orthonormalisation times (a diverging orbit shows here).
    pub max_norm: f64,
    /// Time at the end.
    pub final_time: f64,
    /// State at the end.
    pub final_state: Vec<f64>,
    /// Local (one-interval) exponents, interval-major, `exponents.len()` per interval, in the
    /// sorted order of the final exponents.
    pub local: Vec<f64>,
}

/// Running estimates λ_k(t) = (1/t) Σ log R_kk at each re-orthonormalisation, t measured from
/// the end of the transient: the convergence plot (the study's Fig. 3).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunningEstimates {
    /// Number of exponents per row.
    pub k: usize,
    /// Time since the end of the transient (s).
    pub t: Vec<f64>,
    /// Row-major values, `k` per time, in the sorted order of the final exponents.
    pub values: Vec<f64>,
    /// Running Σλ.
    pub sum: Vec<f64>,
    /// Running ⟨tr J⟩ (NaN without the trace quadrature).
    pub mean_trace: Vec<f64>,
}

impl RunningEstimates {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// No rows recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The running exponents at row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.k..(i + 1) * self.k]
    }

    /// CSV with header `t,lambda1,…,lambdaK,sum,mean_trace`, full precision (round-trip `{:e}`).
    pub fn write_csv<W: Write>(&self, mut out: W) -> io::Result<()> {
        write!(out, "t")?;
        for k in 1..=self.k {
            write!(out, ",lambda{k}")?;
        }
        writeln!(out, ",sum,mean_trace")?;
        for i in 0..self.len() {
            write!(out, "{:e}", self.t[i])?;
            for v in self.row(i) {
                write!(out, ",{v:e}")?;
            }
            writeln!(out, ",{:e},{:e}", self.sum[i], self.mean_trace[i])?;
        }
        Ok(())
    }
}
