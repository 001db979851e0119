//! Margin specifications (`--spec "dpm>=45,dgm>=6dB,ms<=1.6"`) and the region of the Nyquist
//! plane each one forbids. Every supported requirement is "L(jω) stays out of a disk", which is
//! what the tuner linearises (one constraint per frequency per disk).

use std::fmt;
use std::str::FromStr;

use crate::linear::disk::{alpha_from_gain, alpha_from_phase_deg, Disk};
use crate::linear::margins::Margins;

/// One margin requirement.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Requirement {
    /// Balanced disk phase margin ≥ `deg` degrees (`dpm>=45`); 0 < deg < 90.
    DiskPhase {
        /// Degrees.
        deg: f64,
    },
    /// Balanced disk gain margin ≥ `factor` (`dgm>=2` or `dgm>=6dB`); factor > 1.
    DiskGain {
        /// Gain factor (upper end of the disk gain interval).
        factor: f64,
    },
    /// Peak sensitivity ‖S‖∞ ≤ `ms` (`ms<=1.6`); ms > 1.
    PeakSensitivity {
        /// Bound on |S|.
        ms: f64,
    },
    /// Control effort: the peak force of the certificate's tilt recovery ≤ `newtons`
    /// (`force<=500`). The design bounds the force at the start of the recovery, Kp·Φ0 (a
    /// convex bound on Kp); the nonlinear simulation of the certificate checks the peak.
    PeakForce {
        /// Bound on |F| [N].
        newtons: f64,
    },
}

/// A conjunction of requirements. Read from settings as the spec text (`"dpm>=45,dgm>=6dB"`)
/// or in the structured form it is written in; either way through [`FromStr`], which checks
/// the ranges.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "SpecInput")]
pub struct Spec {
    /// All must hold.
    pub requirements: Vec<Requirement>,
}

/// The two ways settings write a spec.
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum SpecInput {
    Text(String),
    Structured { requirements: Vec<Requirement> },
}

impl TryFrom<SpecInput> for Spec {
    type Error = SpecError;
    fn try_from(input: SpecInput) -> Result<Self, SpecError> {
        match input {
            SpecInput::Text(text) => text.parse(),
            SpecInput::Structured { requirements } => Spec { requirements }.to_string().parse(),
        }
    }
}

/// A specification string that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecError {
    /// Not of the form `name>=value` / `name<=value`.
    #[error("cannot read {0:?}: expected e.g. \"dpm>=45\", \"dgm>=6dB\" or \"ms<=1.6\"")]
    Syntax(String),
    /// A quantity the tuner does not know or a wrong comparison for it.
    #[error(
        "unsupported requirement {0:?}: use dpm>= (disk phase margin, deg), dgm>= (disk gain \
         margin, factor or dB) or ms<= (peak sensitivity); the classical phase margin is not a \
         disk constraint"
    )]
    Unsupported(String),
    /// A value outside the meaningful range.
    #[error("{what} must be {range}, got {value}")]
    Range {
        /// Which requirement.
        what: &'static str,
        /// The allowed range.
        range: &'static str,
        /// The value given.
        value: f64,
    },
}

impl FromStr for Spec {
    type Err = SpecError;

    fn from_str(s: &str) -> Result<Self, SpecError> {
        let requirements = s
            .split(',')
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(parse_one)
            .collect::<Result<Vec<_>, _>>()?;
        if requirements.is_empty() {
            return Err(SpecError::Syntax(s.to_string()));
        }
        Ok(Self { requirements })
    }
}

fn parse_one(part: &str) -> Result<Requirement, SpecError> {
    let syntax = || SpecError::Syntax(part.to_string());
    let (name, op, value) = if let Some((n, v)) = part.split_once(">=") {
        (n.trim(), ">=", v.trim())
    } else if let Some((n, v)) = part.split_once("<=") {
        (n.trim(), "<=", v.trim())
    } else {
        return Err(syntax());
    };
    let (number, db) = match value
        .strip_suffix("dB")
        .or_else(|| value.strip_suffix("db"))
    {
        Some(v) => (v.trim(), true),
        None => (value, false),
    };
    let x: f64 = number.parse().map_err(|_| syntax())?;
    if !x.is_finite() {
        return Err(syntax());
    }
    let range = |what, range, ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(SpecError::Range {
                what,
                range,
                value: x,
            })
        }
    };
    match (name.to_ascii_lowercase().as_str(), op, db) {
        ("dpm", ">=", false) => {
            // α ≥ 2 (dpm ≥ 90°) forbids the whole left half-plane, not a disk.
            range("dpm", "in (0, 90) degrees", x > 0.0 && x < 90.0)?;
            Ok(Requirement::DiskPhase { deg: x })
        }
        ("dgm", ">=", _) => {
            let factor = if db { 10f64.powf(x / 20.0) } else { x };
            range("dgm", "> 1 (> 0 dB)", factor > 1.0)?;
            Ok(Requirement::DiskGain { factor })
        }
        ("ms", "<=", false) => {
            range("ms", "> 1", x > 1.0)?;
            Ok(Requirement::PeakSensitivity { ms: x })
        }
        ("force", "<=", false) => {
            range("force", "> 0 N", x > 0.0)?;
            Ok(Requirement::PeakForce { newtons: x })
        }
        _ => Err(SpecError::Unsupported(part.to_string())),
    }
}

impl Requirement {
    /// The disk L(jω) must avoid; `None` for the effort bound, which is no disk.
    pub fn disk(&self) -> Option<Disk> {
        match *self {
            Requirement::DiskPhase { deg } => Some(balanced(alpha_from_phase_deg(deg))),
            Requirement::DiskGain { factor } => Some(balanced(alpha_from_gain(factor))),
            Requirement::PeakSensitivity { ms } => Some(Disk::sensitivity(ms)),
            Requirement::PeakForce { .. } => None,
        }
    }

    /// The requirement scaled by `t` ∈ [0, 1] from trivial (t = 0: stability only) to itself
    /// (t = 1), with `t` > 1 a stricter one: the path the tuner bisects along when the full
    /// requirement cannot be met.
    pub fn scaled(&self, t: f64) -> Self {
        match *self {
            Requirement::DiskPhase { deg } => Requirement::DiskPhase {
                deg: (deg * t).min(89.999),
            },
            Requirement::DiskGain { factor } => Requirement::DiskGain {
                factor: 1.0 + (factor - 1.0) * t,
            },
            Requirement::PeakSensitivity { ms } => Requirement::PeakSensitivity {
                ms: 1.0 + (ms - 1.0) / t.max(1e-12),
            },
            Requirement::PeakForce { newtons } => Requirement::PeakForce {
                newtons: newtons / t.max(1e-12),
            },
        }
    }

    /// Whether verified margins meet the requirement (to 1e-9 relative); the effort bound is
    /// not a margin (the tilt simulation checks it) and counts as met here.
    pub fn met_by(&self, m: &Margins) -> bool {
        let tol = 1e-9;
        m.stable
            && match *self {
                Requirement::DiskPhase { deg } => m.disk.phase_deg >= deg * (1.0 - tol),
                Requirement::DiskGain { factor } => m.disk.gain_high >= factor * (1.0 - tol),
                Requirement::PeakSensitivity { ms } => m.peak_sensitivity <= ms * (1.0 + tol),
                Requirement::PeakForce { .. } => true,
            }
    }
}

fn balanced(alpha: f64) -> Disk {
    // The parser keeps α in (0, 2); the clamp only guards the scaled path.
    Disk::balanced(alpha.clamp(0.0, 2.0 - 1e-9)).unwrap_or(Disk {
        centre: -1.0,
        radius: 0.0,
    })
}

impl Spec {
    /// The effort bound [N], if the spec has one (the smallest, if several).
    pub fn peak_force(&self) -> Option<f64> {
        self.requirements
            .iter()
            .filter_map(|r| match r {
                Requirement::PeakForce { newtons } => Some(*newtons),
                _ => None,
            })
            .reduce(f64::min)
    }

    /// All requirements scaled by `t` (see [`Requirement::scaled`]).
    pub fn scaled(&self, t: f64) -> Self {
        Self {
            requirements: self.requirements.iter().map(|r| r.scaled(t)).collect(),
        }
    }

    /// Whether verified margins meet every requirement.
    pub fn met_by(&self, m: &Margins) -> bool {
        self.requirements.iter().all(|r| r.met_by(m))
    }
}

impl fmt::Display for Spec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self
            .requirements
            .iter()
            .map(|r| match r {
                Requirement::DiskPhase { deg } => format!("dpm>={deg}"),
                Requirement::DiskGain { factor } => format!("dgm>={factor}"),
                Requirement::PeakSensitivity { ms } => format!("ms<={ms}"),
                Requirement::PeakForce { newtons } => format!("force<={newtons}"),
            })
            .collect();
        f.write_str(&parts.join(","))
    }
}
