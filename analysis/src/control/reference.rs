//! Reference signals of the outer loops: piecewise-linear profiles r(t), e.g. the maneuver's
//! forward-velocity reference (start, accelerate, cruise, decelerate, stop).

use serde::{Deserialize, Serialize};

use super::error::ControlError;

/// A piecewise-linear signal through `(t, value)` points, held constant before the first and
/// after the last point. A single point is a constant.
///
/// The reference depends on time only, so it adds nothing to the closed-loop Jacobian in x; its
/// kinks make the vector field non-smooth in t, which RK4 and DOPRI handle with a local error
/// of lower order at the kink (negligible at the default steps).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ProfilePoints")]
pub struct Profile {
    points: Vec<(f64, f64)>,
}

/// A profile as written in settings, checked by [`Profile::new`] when read.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfilePoints {
    points: Vec<(f64, f64)>,
}

impl TryFrom<ProfilePoints> for Profile {
    type Error = ControlError;
    fn try_from(p: ProfilePoints) -> Result<Self, ControlError> {
        Profile::new("reference", p.points)
    }
}

impl Profile {
    /// The constant `value`.
    pub fn constant(value: f64) -> Self {
        Self {
            points: vec![(0.0, value)],
        }
    }

    /// The constant 0 (a reference left out of the settings).
    pub fn zero() -> Self {
        Self::constant(0.0)
    }

    /// Through `points` (at least one; finite; strictly increasing times).
    pub fn new(what: &'static str, points: Vec<(f64, f64)>) -> Result<Self, ControlError> {
        let bad = |why: String| Err(ControlError::InvalidProfile { what, why });
        if points.is_empty() {
            return bad("no points".into());
        }
        if let Some((t, v)) = points
            .iter()
            .find(|(t, v)| !(t.is_finite() && v.is_finite()))
        {
            return bad(format!("point ({t}, {v}) is not finite"));
        }
        if let Some(w) = points.windows(2).find(|w| w[1].0 <= w[0].0) {
            return bad(format!(
                "times must increase, but {} follows {}",
                w[1].0, w[0].0
            ));
        }
        Ok(Self { points })
    }

    /// The study's "start, accelerate, cruise, decelerate, stop" as a trapezoid: 0 until
    /// `t_start`, a ramp to `v_cruise` over `t_ramp`, cruise for `t_cruise`, a ramp back to 0
    /// over `t_ramp`, then rest.
    pub fn trapezoid(
        t_start: f64,
        t_ramp: f64,
        t_cruise: f64,
        v_cruise: f64,
    ) -> Result<Self, ControlError> {
        let t1 = t_start + t_ramp;
        let t2 = t1 + t_cruise;
        let t3 = t2 + t_ramp;
        let mut pts = vec![(t_start, 0.0), (t1, v_cruise), (t2, v_cruise), (t3, 0.0)];
        if t_start > 0.0 {
            pts.insert(0, (0.0, 0.0));
        }
        Self::new("maneuver", pts)
    }

    /// The points.
    pub fn points(&self) -> &[(f64, f64)] {
        &self.points
    }

    /// Time of the last point: after it the profile is constant.
    pub fn t_last(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p.0)
    }

    /// r(t) (no allocation: a linear scan of a handful of points).
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        if t <= p[0].0 {
            return p[0].1;
        }
        for w in p.windows(2) {
            let ((t0, v0), (t1, v1)) = (w[0], w[1]);
            if t <= t1 {
                return v0 + (v1 - v0) * (t - t0) / (t1 - t0);
            }
        }
        p[p.len() - 1].1
    }
}
