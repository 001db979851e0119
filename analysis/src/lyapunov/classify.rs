//! An honest verbal classification of a finite-time spectrum.

use std::fmt;

use serde::{Serialize, Serializer};

/// What the data say about the sign of one exponent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExponentSign {
    /// Above zero by more than its error and the zero band.
    Positive,
    /// Below zero by more than its error and the zero band.
    Negative,
    /// Zero within the error or the zero band, with a small error.
    Zero,
    /// Neither sign nor zero can be claimed: the error is too large.
    Undecided,
}

/// The verdict on a spectrum. Finite-time exponents are estimates: a positive one shows
/// exponential divergence over the horizon, which is chaos only on a bounded, recurrent orbit,
/// and every verdict says so.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Classification {
    /// The orbit rests on an equilibrium (ẋ = 0 along the whole run): the exponents are the real
    /// parts of its Jacobian's eigenvalues, and positive ones are unstable directions, not chaos.
    Equilibrium {
        /// Number of significantly positive exponents.
        unstable: usize,
    },
    /// Every exponent significantly negative.
    StableFixedPoint,
    /// None positive, `zero` consistent with zero, the rest negative.
    Neutral {
        /// Exponents consistent with zero.
        zero: usize,
        /// Exponents in the spectrum.
        of: usize,
    },
    /// `positive` exponents significantly above zero.
    Positive {
        /// Significantly positive exponents.
        positive: usize,
    },
    /// The exponent at `index` (descending order) is `value ± error` (z·stderr) with its sign
    /// undecided: run longer.
    NotConverged {
        /// Index in the sorted spectrum.
        index: usize,
        /// Its estimate.
        value: f64,
        /// z · its standard error.
        error: f64,
    },
}

impl fmt::Display for Classification {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Classification::Equilibrium { unstable: 0 } => write!(
                f,
                "the orbit rests on an equilibrium; no exponent significantly positive: a stable or marginal equilibrium (exponents = real parts of its eigenvalues)"
            ),
            Classification::Equilibrium { unstable } => write!(
                f,
                "the orbit rests on an equilibrium with {unstable} unstable direction(s): exponents = real parts of its eigenvalues; not chaos"
            ),
            Classification::StableFixedPoint => write!(
                f,
                "all exponents < 0 beyond their errors: attracted to a fixed point (finite-time estimate)"
            ),
            Classification::Neutral { zero, of } if zero == of => write!(
                f,
                "all exponents zero within error: regular (periodic, quasi-periodic or integrable) motion, no exponential divergence detected (finite-time estimate)"
            ),
            Classification::Neutral { zero, .. } => write!(
                f,
                "all exponents ≤ 0 within error, {zero} consistent with zero: a marginally stable set (zero exponents come from symmetry directions such as position and heading, and from uncontrolled drift) or a periodic or quasi-periodic attractor (finite-time estimate)"
            ),
            Classification::Positive { positive: 1 } => write!(
                f,
                "one positive exponent significantly above its error: chaotic if the orbit is bounded (finite-time estimate)"
            ),
            Classification::Positive { positive } => write!(
                f,
                "{positive} positive exponents significantly above their errors: hyperchaotic if the orbit is bounded (finite-time estimate)"
            ),
            Classification::NotConverged { index, value, error } => write!(
                f,
                "finite-time estimate, not converged: the sign of λ{} = {value:.4} ± {error:.4} is undecided; run longer",
                index + 1
            ),
        }
    }
}

/// Serialised as its description, the form the `--json` output carries.
impl Serialize for Classification {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// How the signs are decided (from [`LyapunovSettings`](super::LyapunovSettings)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignRule {
    /// z-score for significance.
    pub z: f64,
    /// Fraction of the spectral scale inside which an exponent counts as zero.
    pub zero_band: f64,
    /// Largest z·stderr, as a fraction of the scale, that still allows calling an exponent zero.
    pub convergence_tol: f64,
    /// Averaging horizon (s): the spectral scale is max(max|λ|, 1/horizon), because a
    /// finite-time exponent cannot resolve rates below ~1/horizon (this keeps an all-zero
    /// spectrum from being judged against its own round-off).
    pub horizon: f64,
}

/// The sign of each exponent of a spectrum with its standard errors.
pub fn exponent_signs(exponents: &[f64], stderr: &[f64], rule: &SignRule) -> Vec<ExponentSign> {
    let SignRule {
        z,
        zero_band,
        convergence_tol,
        horizon,
    } = *rule;
    let scale = exponents.iter().fold(1.0 / horizon, |m, l| m.max(l.abs()));
    exponents
        .iter()
        .zip(stderr)
        .map(|(&l, &s)| {
            // A NaN error (too few samples) is as bad as an infinite one.
            let e = if s.is_nan() { f64::INFINITY } else { z * s };
            let band = zero_band * scale;
            if l > e && l > band {
                ExponentSign::Positive
            } else if -l > e && -l > band {
                ExponentSign::Negative
            } else if e <= convergence_tol * scale || (l.abs() <= band && e <= band) {
                ExponentSign::Zero
            } else {
                ExponentSign::Undecided
            }
        })
        .collect()
}

/// The verdict for a spectrum sorted in descending order with its standard errors.
/// `at_equilibrium` says the orbit did not move (ẋ ≈ 0 throughout).
pub fn classify(
    exponents: &[f64],
    stderr: &[f64],
    rule: &SignRule,
    at_equilibrium: bool,
) -> Classification {
    let signs = exponent_signs(exponents, stderr, rule);
    let count = |s: ExponentSign| signs.iter().filter(|&&x| x == s).count();
    if at_equilibrium {
        return Classification::Equilibrium {
            unstable: count(ExponentSign::Positive),
        };
    }
    if let Some(index) = signs.iter().position(|&s| s == ExponentSign::Undecided) {
        return Classification::NotConverged {
            index,
            value: exponents[index],
            error: rule.z * stderr[index],
        };
    }
    match count(ExponentSign::Positive) {
        0 if count(ExponentSign::Zero) == 0 => Classification::StableFixedPoint,
        0 => Classification::Neutral {
            zero: count(ExponentSign::Zero),
            of: exponents.len(),
        },
        positive => Classification::Positive { positive },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts() {
        let rule = SignRule {
            z: 3.0,
            zero_band: 0.01,
            convergence_tol: 0.05,
            horizon: 10.0,
        };
        let c = |l: &[f64], s: &[f64]| classify(l, s, &rule, false);
        assert_eq!(
            c(&[0.9, 0.001, -14.5], &[0.02, 0.01, 0.02]),
            Classification::Positive { positive: 1 }
        );
        assert_eq!(
            c(&[-0.5, -2.0], &[0.01, 0.01]),
            Classification::StableFixedPoint
        );
        assert_eq!(
            c(&[0.001, -2.0], &[0.01, 0.01]),
            Classification::Neutral { zero: 1, of: 2 }
        );
        assert!(matches!(
            c(&[0.3, -1.0], &[0.2, 0.01]),
            Classification::NotConverged { index: 0, .. }
        ));
        let json = serde_json::to_string(&Classification::StableFixedPoint).unwrap();
        assert!(json.starts_with("\"all exponents < 0"));
    }
}
