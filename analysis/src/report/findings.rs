//! Every sentence of the report that judges a result, computed from that result with a stated
//! threshold: checks (which fail the report) and findings (which describe the vehicle). Each is
//! a pure function of library results, so a test can flip it by changing the data.

use serde::Serialize;

use crate::api::{
    complex, LinearReport, LoopVerdict, Recovery, RideVerdict, SimResult, SpectrumResult,
    SteerVerdict, TuneReport, TuneVerdict,
};
use crate::audit::AuditReport;
use crate::lyapunov::{Classification, ExponentSign};
use crate::sweep::{PointResult, Status};

/// Largest |Σλ − ⟨tr J⟩| relative to max(max|λ|, 1/T) that passes: the identity holds up to the
/// integration error, ~1e-12 at the study preset.
pub const TRACE_TOLERANCE: f64 = 1e-8;

/// An overshoot below this fraction of the tilt (0.05 %) counts as none.
pub const NO_OVERSHOOT: f64 = 5e-4;

/// A final forward speed below this [m/s] counts as "at rest".
pub const DRIFT_TOLERANCE: f64 = 0.01;

/// A check that must pass: its failure is shown at the top of the page and fails `twv report`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    /// What was checked.
    pub name: String,
    /// Whether it passed.
    pub passed: bool,
    /// What it found, in a sentence a newcomer reads, with the threshold.
    pub detail: String,
    /// The technical detail behind it (the page shows it on request; may be empty).
    pub more: String,
}

/// A statement about the vehicle, with the verdict it reaches.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Finding {
    /// What it is about.
    pub topic: String,
    /// The verdict in a few words.
    pub verdict: String,
    /// The sentence, with its numbers (rounded to what the test resolves) and threshold.
    pub text: String,
    /// The technical detail behind it (the page shows it on request; may be empty).
    pub more: String,
}

/// `v` with `digits` significant digits, in plain decimal notation (0.0079, 374, 12).
fn significant(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (digits - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.decimals$}")
}

fn finding(topic: &str, verdict: &str, text: String) -> Finding {
    Finding {
        topic: topic.into(),
        verdict: verdict.into(),
        text,
        more: String::new(),
    }
}

/// The audit of every vehicle passed.
pub fn audit_check(audits: &[AuditReport]) -> Check {
    let failed: Vec<&AuditReport> = audits.iter().filter(|a| !a.passed).collect();
    let worst = audits
        .iter()
        .flat_map(|a| a.quantities.iter())
        .fold(0.0_f64, |m, q| m.max(q.max_rel));
    let tol = audits.first().map_or(0.0, |a| a.tolerance);
    let names: Vec<&str> = audits.iter().map(|a| a.model.as_str()).collect();
    Check {
        name: "derived equations vs the independent hand model".into(),
        passed: failed.is_empty() && !audits.is_empty(),
        detail: if failed.is_empty() {
            format!(
                "{}: every entry of M, Cp, F, Q, f and ∂f/∂x agrees (worst normwise relative error \
                 {worst:.1e} ≤ {tol:.0e}) and every physical check passes",
                names.join(", ")
            )
        } else {
            let first: Vec<String> = failed
                .iter()
                .map(|a| {
                    format!(
                        "{}: {}",
                        a.model,
                        a.failures.first().map_or("failed", String::as_str)
                    )
                })
                .collect();
            format!("FAILED for {}", first.join("; "))
        },
        more: String::new(),
    }
}

/// Σλ equals the time average of tr ∂f/∂x (a full spectrum's identity).
pub fn trace_check(s: &SpectrumResult) -> Check {
    let name = "Σλ = ⟨tr ∂f/∂x⟩ along the trajectory".to_string();
    match (s.result.mean_trace, s.result.trace_residual()) {
        (Some(trace), Some(residual)) => Check {
            name,
            passed: residual <= TRACE_TOLERANCE,
            detail: format!(
                "the exponents add up to the trajectory's average divergence ⟨tr ∂f/∂x⟩ = \
                 {trace:.4} 1/s, as every full spectrum must: they agree to {residual:.0e} \
                 (must be ≤ {TRACE_TOLERANCE:.0e})",
            ),
            more: format!(
                "Σλ = {:+.10e} 1/s, ⟨tr J⟩ = {trace:+.10e} 1/s; relative difference {residual:.2e}, \
                 relative to max(max|λ|, 1/T)",
                s.result.sum
            ),
        },
        _ => Check {
            name,
            passed: false,
            detail: "the trace quadrature was off".into(),
            more: String::new(),
        },
    }
}

/// The open-loop spectrum at the study preset and how its largest |λ| scales with the horizon
/// (`horizons`: (horizon [s], exponents), shortest first). A genuine exponent keeps its size; a
/// finite-time transient falls like 1/T. Verdict "transient" when max|λ| falls at least like
/// T^(−1/2) from the shortest to the longest horizon.
pub fn open_loop_finding(preset: &SpectrumResult, horizons: &[(f64, Vec<f64>)]) -> Finding {
    let max_abs = |l: &[f64]| l.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let class = &preset.result.classification;
    let mut text = format!(
        "At the study's {:.0} s horizon: {class}.",
        preset.result.t_total
    );
    let mut more = String::new();
    let verdict = match (horizons.first(), horizons.last()) {
        (Some((t1, l1)), Some((t2, l2))) if t2 > t1 => {
            let (a, b) = (max_abs(l1), max_abs(l2));
            let ratio = if a > 0.0 { b / a } else { 0.0 };
            let transient = b <= a * (t1 / t2).sqrt();
            text += &format!(
                " Over longer horizons the largest |λ| shrinks from {a:.2} 1/s at {t1:.0} s to \
                 {} 1/s at {t2:.0} s: {}.",
                significant(b, 2),
                if transient {
                    "it fades like a finite-time transient, as a conservative system's must"
                } else {
                    "it does not fade: the exponents persist"
                }
            );
            more = format!(
                "max|λ| at {t2:.0} s / at {t1:.0} s = {ratio:.3}; a transient falls like 1/T \
                 (×{:.3} here); the verdict is \"transient\" when the ratio is at most \
                 (T1/T2)^(1/2) = {:.3}.",
                t1 / t2,
                (t1 / t2).sqrt()
            );
            if matches!(class, Classification::Equilibrium { .. }) {
                "an equilibrium"
            } else if transient {
                "finite-time transient, not chaos"
            } else {
                "persistent exponents"
            }
        }
        _ => class.kind(),
    };
    Finding {
        more,
        ..finding("open-loop Lyapunov spectrum", verdict, text)
    }
}

/// The tilt recovery of `sim` (and the drift after it).
pub fn recovery_finding(sim: &SimResult) -> Finding {
    let m = &sim.metrics;
    let tilt = sim.x0.first().copied().unwrap_or(0.0);
    let (verdict, mut text) = match sim.recovery {
        Recovery::Recovered => (
            "recovers",
            format!(
                "{}: Φ recovers from {tilt:+.3} rad in {:.2} s (2 % band) with {}; peak force \
                 {:.0} N.",
                sim.scenario,
                m.phi.settling_time.unwrap_or(0.0),
                m.phi.overshoot.filter(|o| *o >= NO_OVERSHOOT).map_or(
                    "no overshoot".to_string(),
                    |o| format!("{:.1} % overshoot", 100.0 * o)
                ),
                m.peak_force
            ),
        ),
        Recovery::NotSettled => (
            "does not recover",
            format!(
                "{}: Φ does NOT recover from {tilt:+.3} rad within {} s (final Φ = {:+.3e} rad, \
                 peak force {:.0} N).",
                sim.scenario, sim.run.t_end, m.final_phi, m.peak_force
            ),
        ),
        Recovery::Fell => (
            "falls",
            format!(
                "{}: the vehicle FALLS from {tilt:+.3} rad (|Φ| passed the fall angle; peak force \
                 {:.0} N).",
                sim.scenario, m.peak_force
            ),
        ),
    };
    if let (Recovery::Recovered, Some(v)) = (sim.recovery, m.final_v_x) {
        text += &if v.abs() >= DRIFT_TOLERANCE {
            format!(
                " It then rolls on at {v:+.2} m/s (≥ {DRIFT_TOLERANCE} m/s): the pitch loop does \
                 not regulate velocity; an outer velocity loop (twv sim --v-loop KP,KI) removes the \
                 drift."
            )
        } else {
            format!(" It comes to rest (|v_x| < {DRIFT_TOLERANCE} m/s at the end).")
        };
    }
    finding("tilt recovery", verdict, text)
}

/// The study PD's linear pitch loop.
pub fn linear_finding(l: &LinearReport) -> Finding {
    let Some(pitch) = &l.pitch else {
        return finding(
            "linear pitch loop",
            "no loop",
            format!("{} has no pitch (states phi, w_y) to control.", l.model),
        );
    };
    let poles: Vec<String> = pitch.loop_poles.iter().map(complex).collect();
    let (verdict, text) = match (pitch.verdict, &pitch.margins) {
        (LoopVerdict::Stable, Some(m)) => (
            "stable",
            format!(
                "The PD pitch loop (Kp = {}, Kd = {}) is stable: poles {}; balanced disk margin \
                 α = {:.3} (gain [{:.3}, {}], phase ±{:.1}°).",
                l.gains.kp,
                l.gains.kd,
                poles.join(", "),
                m.disk_alpha,
                m.disk_gain_low,
                m.disk_gain_high
                    .map_or("unbounded".into(), |g| format!("{g:.3}")),
                m.disk_phase_deg
            ),
        ),
        (LoopVerdict::NoLoop, _) => (
            "no loop",
            "The force does not reach Φ (the pitch loop's transfer function is zero): nothing to \
             stabilise."
                .to_string(),
        ),
        _ => (
            "unstable",
            format!(
                "The PD pitch loop (Kp = {}, Kd = {}) is UNSTABLE: poles {} (a real part ≥ 0); \
                 margins are undefined.",
                l.gains.kp,
                l.gains.kd,
                poles.join(", ")
            ),
        ),
    };
    finding("linear pitch loop", verdict, text)
}

/// The tuning result.
pub fn tune_finding(t: &TuneReport) -> Finding {
    let gains = t
        .result
        .certificate
        .as_ref()
        .map(|c| format!("Kp = {:.1}, Kd = {:.1}", c.gains.kp, c.gains.kd))
        .unwrap_or_default();
    let (verdict, text) = match t.verdict {
        TuneVerdict::Met => (
            "met",
            format!(
                "Clarabel tuning to {} is met with {gains} (independently certified; the tilt \
                 recovers on the nonlinear model).",
                t.result.spec
            ),
        ),
        TuneVerdict::NonlinearCheckFailed => (
            "nonlinear check failed",
            format!(
                "Tuning to {} meets the linear margins with {gains}, but the nonlinear tilt check \
                 fails.",
                t.result.spec
            ),
        ),
        TuneVerdict::Infeasible => (
            "infeasible",
            format!(
                "Tuning to {} is infeasible: the best gains found reach {:.1} % of it.",
                t.result.spec,
                100.0 * t.result.best_fraction
            ),
        ),
        TuneVerdict::NotVerified => (
            "not verified",
            format!("Tuning to {} ended without verified gains.", t.result.spec),
        ),
    };
    finding("tuned gains", verdict, text)
}

/// Where the map's stability boundary lies along Kp, per row of Kd > 0: between the largest
/// unstable Kp and the smallest stable Kp above it. Compared with the prediction `predicted`
/// (Kp = M_x g for the pitch loop of a pendulum above its hinge): "agrees" when every row's
/// interval holds it, i.e. the boundary is within one grid cell.
pub fn map_finding(points: &[PointResult], predicted: Option<f64>) -> Finding {
    let mut rows: std::collections::BTreeMap<u64, Vec<&PointResult>> = Default::default();
    for p in points.iter().filter(|p| p.kd > 0.0 && p.ki == 0.0) {
        rows.entry(p.kd.to_bits()).or_default().push(p);
    }
    let stable = |p: &PointResult| p.status == Status::Ok && p.value.is_some_and(|v| v < 0.0);
    let mut intervals = Vec::new();
    for row in rows.values() {
        let mut row = row.clone();
        row.sort_by(|a, b| a.kp.total_cmp(&b.kp));
        if let Some(i) = row.iter().position(|p| stable(p)) {
            if row[i..].iter().all(|p| stable(p)) {
                let lo = if i > 0 {
                    row[i - 1].kp
                } else {
                    f64::NEG_INFINITY
                };
                intervals.push((lo, row[i].kp));
            }
        }
    }
    let n_rows = rows.len();
    let (verdict, text) = match (predicted, intervals.len() == n_rows && n_rows > 0) {
        (Some(kp), true) => {
            let inside = intervals.iter().all(|(lo, hi)| *lo <= kp && kp <= *hi);
            let lo = intervals.iter().map(|i| i.0).fold(f64::NEG_INFINITY, f64::max);
            let hi = intervals.iter().map(|i| i.1).fold(f64::INFINITY, f64::min);
            (
                if inside { "agrees" } else { "disagrees" },
                format!(
                    "Along every row Kd > 0 the map turns stable between Kp = {lo:.0} and {hi:.0} \
                     N/rad; the prediction Kp = M_x g = {kp:.1} N/rad {} (test: within one grid \
                     cell on every row).",
                    if inside { "lies inside" } else { "lies OUTSIDE" }
                ),
            )
        }
        (None, true) => (
            "computed",
            "The upright is not open-loop unstable here, so the prediction Kp > M_x g does not \
             apply; the boundary drawn is the map's own zero contour."
                .to_string(),
        ),
        (_, false) => (
            "no single boundary",
            format!(
                "{} of {n_rows} rows with Kd > 0 have one stable Kp range to their right; no single \
                 boundary along Kp to compare with Kp = M_x g.",
                intervals.len()
            ),
        ),
    };
    finding("stability map", verdict, text)
}

/// A row of the claims table: the study's claim, the verdict, the evidence.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Claim {
    /// The study's claim.
    pub claim: String,
    /// The verdict on it.
    pub verdict: String,
    /// Why.
    pub evidence: String,
}

/// "Three positive Lyapunov exponents: hyperchaos": judged at the longest horizon computed
/// (`longest`), where a genuine positive exponent is still significant and a transient is not.
pub fn hyperchaos_claim(at_study: &SpectrumResult, longest: &SpectrumResult) -> Claim {
    let positive = |s: &SpectrumResult| {
        s.result
            .signs
            .iter()
            .filter(|d| d.sign == ExponentSign::Positive)
            .count()
    };
    let verdict = match longest.result.classification {
        Classification::Positive { positive } if positive >= 2 => "Reproduced",
        Classification::Positive { .. } => "Not reproduced (one positive exponent)",
        Classification::NotConverged { .. } => "Inconclusive (not converged)",
        _ => "Not reproduced",
    };
    Claim {
        claim: "Three positive Lyapunov exponents: the open-loop vehicle is hyperchaotic".into(),
        verdict: verdict.into(),
        evidence: format!(
            "{} significantly positive exponent(s) at the study's {:.0} s horizon ({}); {} at \
             {:.0} s ({}).",
            positive(at_study),
            at_study.result.t_total,
            at_study.result.classification.kind(),
            positive(longest),
            longest.result.t_total,
            longest.result.classification
        ),
    }
}

/// "Under PD control all exponents become negative", from the closed-loop spectrum's signs.
pub fn pd_exponents_claim(closed: &SpectrumResult) -> Claim {
    let count = |s: ExponentSign| closed.result.signs.iter().filter(|d| d.sign == s).count();
    let (neg, zero, pos, und) = (
        count(ExponentSign::Negative),
        count(ExponentSign::Zero),
        count(ExponentSign::Positive),
        count(ExponentSign::Undecided),
    );
    let verdict = if pos > 0 {
        "Not reproduced"
    } else if und > 0 {
        "Inconclusive"
    } else if zero > 0 {
        "Partly"
    } else {
        "Reproduced"
    };
    let values: Vec<String> = closed
        .result
        .exponents
        .iter()
        .map(|l| format!("{l:+.4}"))
        .collect();
    let mut evidence = format!(
        "Closed-loop spectrum {}: {neg} negative, {zero} zero, {pos} positive, {und} undecided \
         (3σ and floor tests).",
        values.join(", ")
    );
    let note = closed.drift_note();
    if zero > 0 && !note.is_empty() {
        evidence += &format!(" The zero ones: {note}; a pitch loop does not act on them.");
    }
    Claim {
        claim: "Under PD control all Lyapunov exponents become negative".into(),
        verdict: verdict.into(),
        evidence,
    }
}

/// "PID control stabilises the vehicle after forward and backward tilts".
pub fn recovery_claim(runs: &[SimResult]) -> Claim {
    let recovered = runs
        .iter()
        .filter(|r| r.recovery == Recovery::Recovered)
        .count();
    let verdict = if recovered == runs.len() && !runs.is_empty() {
        "Reproduced for the pitch"
    } else if recovered > 0 {
        "Partly"
    } else {
        "Not reproduced"
    };
    let parts: Vec<String> = runs.iter().map(|r| recovery_finding(r).text).collect();
    Claim {
        claim: "PID control stabilises the vehicle after forward and backward tilts".into(),
        verdict: verdict.into(),
        evidence: parts.join(" "),
    }
}

/// "The equations (ProPac, Mathematica) are correct", from the audit.
pub fn equations_claim(audit: &Check) -> Claim {
    Claim {
        claim: "The equations of motion are correct".into(),
        verdict: if audit.passed {
            "Checked independently here".into()
        } else {
            "Check FAILED".into()
        },
        evidence: audit.detail.clone(),
    }
}

/// The bicycle: where it is self-stable, whether the tuned schedule balances it at every speed,
/// and what a push below the weave speed does unsteered and steered.
pub fn bicycle_finding(b: &super::sections::BicycleSection) -> Finding {
    use super::sections::{PUSH, PUSH_SPEED};
    let n = b.steer.points.len();
    let met = b.steer.points.iter().filter(|p| p.met).count();
    let (lo, hi) = (
        b.steer.points.first().map_or(f64::NAN, |p| p.speed),
        b.steer.points.last().map_or(f64::NAN, |p| p.speed),
    );
    let stable = match (b.steady.weave_speed, b.steady.capsize_speed) {
        (Some(w), Some(c)) => format!("is self-stable from {w:.2} to {c:.2} m/s"),
        _ => "is self-stable nowhere between weave and capsize".to_string(),
    };
    let fell = matches!(b.unsteered.verdict, RideVerdict::Fell);
    let recovered = matches!(b.steered.verdict, RideVerdict::Recovered);
    let text = format!(
        "Nobody steering, the bicycle {stable}. Steered by a gain schedule tuned to {}, it \
         meets the spec, and a {PUSH} rad/s lean-rate push dies out, at {met} of {n} speeds \
         from {lo} to {hi} m/s. At {PUSH_SPEED} m/s the push {} nobody steering and {} steered.",
        b.steer.spec,
        if fell {
            "makes it fall"
        } else {
            "does not make it fall"
        },
        if recovered {
            "dies out"
        } else {
            "does not die out"
        },
    );
    let verdict = if matches!(b.steer.verdict, SteerVerdict::Met) && fell && recovered {
        "balanced by steering at every speed"
    } else {
        "not balanced at every speed"
    };
    finding("the bicycle", verdict, text)
}
