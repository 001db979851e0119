//! An honest verbal classification of a finite-time spectrum.
//!
//! Each exponent's sign is decided from its own standard error and an absolute floor, never
//! from the size of the other exponents: a large negative exponent (a strongly contracting
//! direction) must not make a small positive one look like zero. The largest |λ| only sets the
//! resolution below which an exponent whose sign is not significant still counts as zero rather
//! than as "not converged".

use std::fmt;

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::LyapunovSettings;

/// What the data say about the sign of one exponent.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExponentSign {
    /// Above zero by more than z·σ and the floor.
    Positive,
    /// Below zero by more than z·σ and the floor.
    Negative,
    /// Not significantly signed, with an error bar inside the resolution.
    Zero,
    /// Neither sign nor zero can be claimed: the error bar is larger than the resolution.
    Undecided,
}

/// Which test decided an exponent's sign.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SignTest {
    /// |λ| exceeds both z·σ and the floor: the sign is significant.
    Significant,
    /// |λ| is within z·σ or the floor, and z·σ is within the resolution: zero.
    WithinResolution,
    /// |λ| is within z·σ, and z·σ exceeds the resolution: the sign is not resolved.
    ErrorTooLarge,
}

impl fmt::Display for SignTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SignTest::Significant => "|λ| > z·σ and > floor",
            SignTest::WithinResolution => "|λ| ≤ max(z·σ, floor), z·σ ≤ resolution",
            SignTest::ErrorTooLarge => "|λ| ≤ z·σ, z·σ > resolution",
        })
    }
}

/// How one exponent's sign was decided, with the numbers the test used.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SignDecision {
    /// The verdict.
    pub sign: ExponentSign,
    /// The error bar z·σ (σ the batch-means standard error); `None` when σ is unknown (too few
    /// intervals), which counts as an infinite error.
    pub error: Option<f64>,
    /// The test that decided.
    pub test: SignTest,
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
    /// The exponent at `index` (descending order) is `value ± error` (z·σ) with its sign
    /// undecided: run longer.
    NotConverged {
        /// Index in the sorted spectrum.
        index: usize,
        /// Its estimate.
        value: f64,
        /// z · its standard error.
        error: f64,
        /// The z-score.
        z: f64,
    },
}

impl Classification {
    /// A short machine-readable name of the verdict.
    pub fn kind(&self) -> &'static str {
        match self {
            Classification::Equilibrium { .. } => "equilibrium",
            Classification::StableFixedPoint => "stable_fixed_point",
            Classification::Neutral { .. } => "neutral",
            Classification::Positive { positive: 1 } => "chaotic",
            Classification::Positive { .. } => "hyperchaotic",
            Classification::NotConverged { .. } => "not_converged",
        }
    }
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
                "all exponents significantly negative: attracted to a fixed point (finite-time estimate)"
            ),
            Classification::Neutral { zero, of } if zero == of => write!(
                f,
                "all exponents zero within their errors: regular (periodic, quasi-periodic or integrable) motion, no exponential divergence detected (finite-time estimate)"
            ),
            Classification::Neutral { zero, .. } => write!(
                f,
                "no exponent significantly positive, {zero} zero within their errors: no exponential divergence detected; a marginally stable set (drift or symmetry directions) or a periodic or quasi-periodic attractor (finite-time estimate)"
            ),
            Classification::Positive { positive: 1 } => write!(
                f,
                "one exponent significantly positive: chaotic if the orbit is bounded (finite-time estimate)"
            ),
            Classification::Positive { positive } => write!(
                f,
                "{positive} exponents significantly positive: hyperchaotic if the orbit is bounded (finite-time estimate)"
            ),
            Classification::NotConverged {
                index,
                value,
                error,
                z,
            } => write!(
                f,
                "finite-time estimate, not converged: the sign of λ{} = {value:+.4} ± {error:.4} ({z}σ) is undecided; run longer",
                index + 1
            ),
        }
    }
}

/// Serialised as `{"kind": …, "text": …}` (plus the counts of the verdict).
impl Serialize for Classification {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        map.serialize_entry("kind", self.kind())?;
        match *self {
            Classification::Equilibrium { unstable } => {
                map.serialize_entry("unstable", &unstable)?
            }
            Classification::Neutral { zero, .. } => map.serialize_entry("zero", &zero)?,
            Classification::Positive { positive } => map.serialize_entry("positive", &positive)?,
            Classification::NotConverged { index, .. } => map.serialize_entry("index", &index)?,
            Classification::StableFixedPoint => {}
        }
        map.serialize_entry("text", &self.to_string())?;
        map.end()
    }
}

/// How the signs are decided.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignRule {
    /// z-score for significance.
    pub z: f64,
    /// Absolute floor [1/s]: |λ| at or below it is never called significant.
    pub floor: f64,
    /// An exponent that is not significant counts as zero when its error bar z·σ is at most
    /// this [1/s], else as undecided.
    pub resolution: f64,
}

impl SignRule {
    /// The rule of `settings` for a run of horizon `t_total` whose exponents are `exponents`.
    ///
    /// The default floor is ln(K²)/T over K intervals of a horizon T (at least 1/T): the
    /// finite-time exponent of a tangent vector that grows only like t² over the run, as along
    /// a marginal direction with a shear or a double zero eigenvalue, so polynomial growth is
    /// not taken for exponential divergence. The resolution is the larger of the floor and
    /// `convergence_tol` · max|λ|.
    pub fn from_settings(settings: &LyapunovSettings, t_total: f64, exponents: &[f64]) -> Self {
        let intervals = (t_total / settings.t_sample).round().max(1.0);
        let floor = settings
            .zero_floor
            .unwrap_or_else(|| (2.0 * intervals.ln()).max(1.0) / t_total);
        let largest = exponents.iter().fold(0.0_f64, |m, l| m.max(l.abs()));
        Self {
            z: settings.significance,
            floor,
            resolution: floor.max(settings.convergence_tol * largest),
        }
    }

    /// The sign of one exponent with its standard error.
    pub fn decide(&self, value: f64, stderr: f64) -> SignDecision {
        // A NaN error (too few samples) is as bad as an infinite one.
        let error = (!stderr.is_nan()).then_some(self.z * stderr);
        let e = error.unwrap_or(f64::INFINITY);
        let beyond = e.max(self.floor);
        let (sign, test) = if value > beyond {
            (ExponentSign::Positive, SignTest::Significant)
        } else if -value > beyond {
            (ExponentSign::Negative, SignTest::Significant)
        } else if e <= self.resolution {
            (ExponentSign::Zero, SignTest::WithinResolution)
        } else {
            (ExponentSign::Undecided, SignTest::ErrorTooLarge)
        };
        SignDecision { sign, error, test }
    }
}

/// The verdict and the per-exponent decisions for a spectrum sorted in descending order with
/// its standard errors. `at_equilibrium` says the orbit did not move (ẋ ≈ 0 throughout).
pub fn classify(
    exponents: &[f64],
    stderr: &[f64],
    rule: &SignRule,
    at_equilibrium: bool,
) -> (Classification, Vec<SignDecision>) {
    let signs: Vec<SignDecision> = exponents
        .iter()
        .zip(stderr)
        .map(|(&l, &s)| rule.decide(l, s))
        .collect();
    let verdict = verdict(exponents, &signs, rule.z, at_equilibrium);
    (verdict, signs)
}

/// The verdict from per-exponent decisions (`exponents` sorted descending, z the z-score).
pub fn verdict(
    exponents: &[f64],
    signs: &[SignDecision],
    z: f64,
    at_equilibrium: bool,
) -> Classification {
    let count = |s: ExponentSign| signs.iter().filter(|d| d.sign == s).count();
    if at_equilibrium {
        Classification::Equilibrium {
            unstable: count(ExponentSign::Positive),
        }
    } else if let Some(index) = signs.iter().position(|d| d.sign == ExponentSign::Undecided) {
        Classification::NotConverged {
            index,
            value: exponents[index],
            error: signs[index].error.unwrap_or(f64::INFINITY),
            z,
        }
    } else {
        match count(ExponentSign::Positive) {
            0 if count(ExponentSign::Zero) == 0 => Classification::StableFixedPoint,
            0 => Classification::Neutral {
                zero: count(ExponentSign::Zero),
                of: exponents.len(),
            },
            positive => Classification::Positive { positive },
        }
    }
}
