//! The result of a run: the summary that serialises to the `--json` form, the running
//! estimates (CSV), and run details.

use std::io::{self, Write};

use serde::Serialize;

use super::{Classification, SignDecision};

/// A Lyapunov spectrum with its diagnostics.
///
/// Serialises (serde) to the `twv lyap --json` object `{"exponents", "stderr", "significance",
/// "zero_floor", "signs", "sum", "mean_trace", "kaplan_yorke", "classification", "t_total"}`;
/// the running estimates and run details are kept out of it and written separately
/// ([`RunningEstimates::write_csv`]).
#[derive(Debug, Clone, Serialize)]
pub struct LyapunovResult {
    /// The exponents λ_1 ≥ … ≥ λ_K (1/s).
    pub exponents: Vec<f64>,
    /// Batch-means standard error σ of each exponent (same order; one standard error, not z·σ).
    pub stderr: Vec<f64>,
    /// The z-score of the sign tests: an exponent is significant beyond z·σ.
    pub significance: f64,
    /// The absolute floor of the sign tests [1/s].
    pub zero_floor: f64,
    /// How each exponent's sign was decided (same order).
    pub signs: Vec<SignDecision>,
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
    /// The `k` largest exponents of a spectrum computed with more (what a run of `k` tangent
    /// vectors gives: the first `k` columns of a QR do not depend on the later ones). Each kept
    /// exponent keeps its sign decision; Σλ, the running estimates and the verdict are those of
    /// the kept ones; ⟨tr J⟩ and the Kaplan–Yorke dimension, known from the full spectrum, stay.
    pub fn largest(mut self, k: usize) -> Self {
        let k = k.clamp(1, self.exponents.len());
        let n = self.exponents.len();
        self.exponents.truncate(k);
        self.stderr.truncate(k);
        self.signs.truncate(k);
        self.sum = self.exponents.iter().sum();
        let r = &mut self.running;
        r.values = r
            .values
            .chunks_exact(n)
            .flat_map(|row| row[..k].iter().copied())
            .collect();
        r.sum = (0..r.t.len())
            .map(|i| r.values[i * k..(i + 1) * k].iter().sum())
            .collect();
        r.k = k;
        self.classification = super::classify::verdict(
            &self.exponents,
            &self.signs,
            self.significance,
            self.details.at_equilibrium,
        );
        self.details.full_spectrum = k == n && self.details.full_spectrum;
        self
    }

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
}

/// Running estimates λ_k(t) = (1/t) Σ log R_kk at the re-orthonormalisations, t measured from
/// the end of the transient: the convergence plot (the study's Fig. 3). Every interval up to
/// [`MAX_RUNNING_ROWS`](super::MAX_RUNNING_ROWS) intervals, evenly thinned beyond (the last
/// interval always kept).
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
