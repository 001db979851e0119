//! The audit's result: a table a person can read, JSON for machines, and the verdict.

use std::fmt::Write;

use serde::Serialize;

use super::compare::QuantityError;
use super::physics::PhysicsCheck;
use super::sampling::Sample;
use super::AuditSettings;

/// Everything an audit found.
#[derive(Debug, Clone, Serialize)]
pub struct AuditReport {
    pub model: String,
    pub samples: usize,
    pub seed: u64,
    pub tolerance: f64,
    pub quantities: Vec<QuantityError>,
    pub physics: Vec<PhysicsCheck>,
    pub passed: bool,
    /// One line per failed check, naming the quantity/equation and the worst state.
    pub failures: Vec<String>,
}

/// The per-quantity rows of an audit's table (the built-in audit's and a hand file's).
pub(crate) fn quantity_table(quantities: &[QuantityError], tolerance: f64) -> String {
    let mut s = format!(
        "  {:<8} {:>12} {:>12}  {:<22} status\n",
        "quantity", "max abs", "max rel", "worst entry"
    );
    for q in quantities {
        // Asked this way round so that a NaN error fails.
        let ok = if q.max_rel <= tolerance { "ok" } else { "FAIL" };
        let _ = writeln!(
            s,
            "  {:<8} {:>12.3e} {:>12.3e}  {:<22} {ok}",
            q.quantity, q.max_abs, q.max_rel, q.worst_entry
        );
    }
    s
}

fn format_state(x: &[f64]) -> String {
    let parts: Vec<String> = x.iter().map(|v| format!("{v:.6}")).collect();
    format!("[{}]", parts.join(", "))
}

impl AuditReport {
    pub fn new<const NX: usize, const NU: usize>(
        model: &str,
        settings: &AuditSettings,
        quantities: Vec<QuantityError>,
        physics: Vec<PhysicsCheck>,
        samples: &[Sample<NX, NU>],
    ) -> Self {
        let mut failures = Vec::new();
        for q in &quantities {
            // Asked this way round so that a NaN error fails.
            let within = q.max_rel <= settings.tolerance;
            if !within {
                let s = &samples[q.worst_sample];
                failures.push(format!(
                    "{}: relative error {:.3e} in {} > {:.0e} at x = {}, u = {}",
                    q.quantity,
                    q.max_rel,
                    q.worst_entry,
                    settings.tolerance,
                    format_state(&s.x),
                    format_state(&s.u)
                ));
            }
        }
        for c in physics.iter().filter(|c| !c.passed) {
            failures.push(format!(
                "{}: error {:.3e} > {:.0e} ({})",
                c.name, c.error, c.tolerance, c.detail
            ));
        }
        Self {
            model: model.to_string(),
            samples: samples.len(),
            seed: settings.seed,
            tolerance: settings.tolerance,
            passed: failures.is_empty(),
            quantities,
            physics,
            failures,
        }
    }

    /// The table printed by `twv audit`.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "audit {}: generated vs hand model, {} samples (seed {}), tolerance {:.0e} relative",
            self.model, self.samples, self.seed, self.tolerance
        );
        s.push_str(&quantity_table(&self.quantities, self.tolerance));
        let _ = writeln!(
            s,
            "  {:<34} {:>12} {:>10}  status",
            "physical check", "error", "tolerance"
        );
        for c in &self.physics {
            let ok = if c.passed { "ok" } else { "FAIL" };
            let _ = writeln!(
                s,
                "  {:<34} {:>12.3e} {:>10.0e}  {ok}",
                c.name, c.error, c.tolerance
            );
        }
        let verdict = if self.passed { "PASSED" } else { "FAILED" };
        let _ = writeln!(s, "  {verdict}");
        for f in &self.failures {
            let _ = writeln!(s, "  - {f}");
        }
        s
    }
}
