//! The grid: gain axes `A:B:N` and model-parameter axes `NAME=A:B:N`, and the row-major order
//! that gives every point a fixed index.
//!
//! Order: Kp varies fastest, then Kd, then Ki, then each parameter axis in the order given —
//! `index = ((i_p · N_ki + i_ki) · N_kd + i_kd) · N_kp + i_kp` for one parameter axis. One row
//! of the map (fixed Kd, Ki, parameters) is therefore a contiguous index range, the points of
//! one parameter setting are a contiguous block, and a point's gains and parameters depend only
//! on its index.

use serde::{Deserialize, Serialize};

use super::error::SweepError;
use crate::linear::PidGains;

/// `N` values evenly spaced from `lo` to `hi` inclusive (`N = 1`: just `lo`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub n: usize,
}

impl Axis {
    /// The axis of one value.
    pub fn point(v: f64) -> Self {
        Self { lo: v, hi: v, n: 1 }
    }

    /// Parses `A:B:N` for option `--{name}`.
    pub fn parse(name: &'static str, text: &str) -> Result<Self, SweepError> {
        let bad = |reason: &str| SweepError::Axis {
            axis: name,
            text: text.to_string(),
            reason: reason.to_string(),
        };
        let parts: Vec<&str> = text.split(':').map(str::trim).collect();
        let [lo, hi, n] = parts[..] else {
            return Err(bad("three fields separated by `:`"));
        };
        let num = |s: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(&format!("`{s}` is not a finite number")))
        };
        let (lo, hi) = (num(lo)?, num(hi)?);
        let n: usize = n
            .parse()
            .map_err(|_| bad(&format!("`{n}` is not a count")))?;
        if n == 0 {
            return Err(bad("the count N must be ≥ 1"));
        }
        if n > 1 && hi <= lo {
            return Err(bad("need A < B when N > 1"));
        }
        Ok(Self { lo, hi, n })
    }

    /// The `i`-th value, computed from `i` alone (no accumulated sums), so every shard agrees.
    pub fn value(&self, i: usize) -> f64 {
        if self.n == 1 {
            self.lo
        } else if i + 1 == self.n {
            self.hi
        } else {
            self.lo + (self.hi - self.lo) * (i as f64 / (self.n - 1) as f64)
        }
    }

    /// Distance between neighbouring values (0 for one value).
    pub fn spacing(&self) -> f64 {
        if self.n > 1 {
            (self.hi - self.lo) / (self.n - 1) as f64
        } else {
            0.0
        }
    }

    /// All values.
    pub fn values(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.value(i)).collect()
    }
}

/// The name of the operating-point axis over the initial tilt Φ0 [rad] of the nonlinear
/// metrics (`--param tilt=A:B:N`): not a model parameter, the state the runs start from.
pub const TILT_AXIS: &str = "tilt";

/// A model parameter swept over `n` values from `lo` to `hi` (the IR's parameter name: `m2`,
/// `I2_xx`, …), or the initial tilt ([`TILT_AXIS`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamAxis {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
    pub n: usize,
}

impl ParamAxis {
    /// Parses `NAME=A:B:N` (the option `--param`).
    pub fn parse(text: &str) -> Result<Self, SweepError> {
        let bad = |reason: &str| SweepError::Axis {
            axis: "param",
            text: text.to_string(),
            reason: reason.to_string(),
        };
        let (name, axis) = text
            .split_once('=')
            .ok_or_else(|| bad("NAME=A:B:N (a parameter name, `=`, then the axis)"))?;
        let name = name.trim();
        if name.is_empty() {
            return Err(bad("a parameter name before `=`"));
        }
        let a = Axis::parse("param", axis).map_err(|e| match e {
            SweepError::Axis { reason, .. } => bad(&reason),
            other => other,
        })?;
        Ok(Self {
            name: name.to_string(),
            lo: a.lo,
            hi: a.hi,
            n: a.n,
        })
    }

    /// The values as an [`Axis`].
    pub fn axis(&self) -> Axis {
        Axis {
            lo: self.lo,
            hi: self.hi,
            n: self.n,
        }
    }
}

/// The (Kp, Kd[, Ki]) grid, and the model parameters swept with it; without a Ki axis Ki = 0
/// (a PD law). Gain-only grids serialise as before (no `params` field), so their shard files
/// and hashes are unchanged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    pub kp: Axis,
    pub kd: Axis,
    pub ki: Option<Axis>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub params: Vec<ParamAxis>,
}

impl Grid {
    /// The study's gain square, Kp 0–8000 N/rad × Kd 0–4000 N s/rad, at `n` × `n` points (what
    /// the report and the map benchmark draw).
    pub fn study_gains(n: usize) -> Self {
        Self {
            kp: Axis {
                lo: 0.0,
                hi: 8000.0,
                n,
            },
            kd: Axis {
                lo: 0.0,
                hi: 4000.0,
                n,
            },
            ki: None,
            params: Vec::new(),
        }
    }

    /// Number of Ki values (1 without a Ki axis).
    pub fn n_ki(&self) -> usize {
        self.ki.map_or(1, |a| a.n)
    }

    /// Number of points of one (Kp, Kd) map.
    pub fn map_len(&self) -> usize {
        self.kp.n * self.kd.n
    }

    /// Number of points of one parameter setting (the gain grid).
    pub fn gain_len(&self) -> usize {
        self.map_len() * self.n_ki()
    }

    /// Number of parameter settings (1 without parameter axes).
    pub fn n_settings(&self) -> usize {
        self.params.iter().map(|a| a.n).product()
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.gain_len() * self.n_settings()
    }

    /// Which parameter setting a point belongs to (0 without parameter axes).
    pub fn setting(&self, index: usize) -> usize {
        index / self.gain_len()
    }

    /// (name, value) of every parameter axis at setting `k`, the first axis fastest.
    pub fn param_values(&self, setting: usize) -> Vec<(String, f64)> {
        let mut rest = setting;
        self.params
            .iter()
            .map(|a| {
                let i = rest % a.n;
                rest /= a.n;
                (a.name.clone(), a.axis().value(i))
            })
            .collect()
    }

    /// The initial tilt of setting `setting`, if the grid has a [`TILT_AXIS`].
    pub fn tilt(&self, setting: usize) -> Option<f64> {
        self.param_values(setting)
            .into_iter()
            .find(|(n, _)| n == TILT_AXIS)
            .map(|(_, v)| v)
    }

    /// The model parameters of setting `setting` (the parameter axes less the tilt).
    pub fn model_values(&self, setting: usize) -> Vec<(String, f64)> {
        let mut v = self.param_values(setting);
        v.retain(|(n, _)| n != TILT_AXIS);
        v
    }

    /// Every axis in index order (fastest first) with its label: Kp, Kd, Ki (if any), then the
    /// parameters.
    pub fn axes(&self) -> Vec<(String, Axis)> {
        let mut out = vec![
            ("Kp [N/rad]".to_string(), self.kp),
            ("Kd [N s/rad]".to_string(), self.kd),
        ];
        out.extend(self.ki.map(|a| ("Ki [N/(rad s)]".to_string(), a)));
        out.extend(self.params.iter().map(|p| {
            let label = if p.name == TILT_AXIS {
                "initial tilt Φ0 [rad]".to_string()
            } else {
                p.name.clone()
            };
            (label, p.axis())
        }));
        out
    }

    /// Whether the grid is empty (never, for parsed axes).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// (i_kp, i_kd, i_ki) of a point (see the module documentation for the order).
    pub fn coords(&self, index: usize) -> (usize, usize, usize) {
        let index = index % self.gain_len();
        let i_kp = index % self.kp.n;
        let rest = index / self.kp.n;
        (i_kp, rest % self.kd.n, rest / self.kd.n)
    }

    /// The gains of a point.
    pub fn gains(&self, index: usize) -> PidGains {
        let (i, j, k) = self.coords(index);
        PidGains {
            kp: self.kp.value(i),
            ki: self.ki.map_or(0.0, |a| a.value(k)),
            kd: self.kd.value(j),
        }
    }
}
