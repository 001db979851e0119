//! One grid point's result, and how a simulation that fails is recorded rather than aborting
//! the sweep.

use serde::{Deserialize, Serialize};

/// How a point's computation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// The metric has a value.
    Ok,
    /// |Φ| passed the fall angle: the vehicle fell over (no value).
    Fell,
    /// The integration became non-finite (no value).
    BlewUp,
    /// The run ended inside time but Φ never stayed in its 2 % band (settling time only).
    NotSettled,
    /// Anything else (a degenerate tangent basis, an eigenvalue failure); no value.
    Failed,
}

impl Status {
    /// How figures and tables name it.
    pub fn label(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Fell => "fell",
            Status::BlewUp => "blew up",
            Status::NotSettled => "not settled",
            Status::Failed => "failed",
        }
    }
}

/// The result at one grid index.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    pub index: usize,
    pub kp: f64,
    pub ki: f64,
    pub kd: f64,
    /// The metric, `None` unless `status` is `ok` (JSON has no NaN or ∞).
    pub value: Option<f64>,
    pub status: Status,
    /// When the max-Lyapunov run came to rest and the rest of its horizon was computed from
    /// the linearisation there [s] (the settled tail, `sweep::settle`); absent when every step
    /// was taken.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settled_at: Option<f64>,
}

impl PointResult {
    /// Which side of the stability boundary the point is on, as a number whose zero contour is
    /// the boundary: the value itself for the spectral abscissa and λ1 (negative = stable),
    /// −1 for a settled run; +1 for a fall, blow-up or unsettled run; NaN if unknown.
    pub fn stability_indicator(&self, signed_value: bool) -> f64 {
        match (self.status, self.value) {
            (Status::Ok, Some(v)) if signed_value => v,
            (Status::Ok, Some(_)) => -1.0,
            (Status::Fell | Status::BlewUp | Status::NotSettled, _) => 1.0,
            _ => f64::NAN,
        }
    }
}
