"""Result objects: the job's JSON (exactly what `twv <job> --json` prints) as `.raw`, with the
numbers a notebook wants as NumPy arrays."""

from __future__ import annotations

import io
from typing import Any

import numpy as np


class Result:
    """A job's result. `raw` is the JSON object; keys are also attributes."""

    def __init__(self, raw: dict[str, Any]):
        self.raw = raw

    def __getattr__(self, name: str):
        try:
            return self.raw[name]
        except KeyError:
            raise AttributeError(name) from None

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(self.raw)})"


def _csv(text: str | None) -> tuple[list[str], np.ndarray]:
    if not text:
        return [], np.zeros((0, 0))
    header, _, body = text.partition("\n")
    columns = header.split(",")
    data = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2) if body.strip() else None
    return columns, (data if data is not None else np.zeros((0, len(columns))))


class SpectrumResult(Result):
    """A Lyapunov spectrum: exponents λ1 ≥ … [1/s], batch-means stderr (1σ), Σλ, ⟨tr J⟩,
    Kaplan–Yorke dimension, the verdict, and the running estimates."""

    def __init__(self, raw: dict[str, Any], csv: str | None):
        super().__init__(raw)
        columns, data = _csv(csv)
        k = len(raw["exponents"])
        self.t = data[:, 0] if data.size else np.zeros(0)
        """Time since the transient [s] of each running estimate."""
        self.running = data[:, 1 : 1 + k] if data.size else np.zeros((0, k))
        """Running exponents, one row per re-orthonormalisation."""
        self.running_sum = data[:, 1 + k] if data.size else np.zeros(0)

    @property
    def exponents(self) -> np.ndarray:
        return np.array(self.raw["exponents"])

    @property
    def stderr(self) -> np.ndarray:
        return np.array(self.raw["stderr"])

    @property
    def classification(self) -> str:
        """`equilibrium`, `stable_fixed_point`, `neutral`, `chaotic`, `hyperchaotic` or
        `not_converged` (the text is `raw["classification"]["text"]`)."""
        return self.raw["classification"]["kind"]


class _SeriesResult(Result):
    """A result with a time series: `columns`, `data`, `series[name]` and `t`."""

    def __init__(self, raw: dict[str, Any], csv: str | None):
        super().__init__(raw)
        self.columns, self.data = _csv(csv)
        self.series = {c: self.data[:, i] for i, c in enumerate(self.columns)}
        self.t = self.series.get("t", np.zeros(0))


class SimResult(_SeriesResult):
    """A closed-loop run: the time series (`series[name]`, `t`), metrics, how it ended and
    whether the pitch recovered."""

    @property
    def recovered(self) -> bool:
        return self.raw["recovery"] == "recovered"


class RideResult(_SeriesResult):
    """An uncontrolled run: the time series (`series[name]`, `t`), how it ended and the
    verdict on the watched state."""

    @property
    def verdict(self) -> str:
        return self.raw["verdict"]


class LinearResult(Result):
    """The linearisation: open-loop modes, the PID pitch loop (poles, margins) and the LQR."""

    @property
    def loop_poles(self) -> np.ndarray:
        return np.array([complex(*p) for p in self.raw["pitch"]["loop_poles"]])

    @property
    def margins(self) -> dict[str, Any] | None:
        """Gain, phase, delay and disk margins of a stable loop (None otherwise)."""
        return self.raw["pitch"]["margins"]

    @property
    def lqr(self) -> dict[str, Any]:
        return self.raw["lqr"]


class TuneResult(Result):
    """Tuned gains with their status and certificate (margins re-computed independently, the
    nonlinear tilt check)."""

    @property
    def verdict(self) -> str:
        """`met`, `nonlinear_check_failed`, `infeasible` or `not_verified`."""
        return self.raw["verdict"]

    @property
    def met(self) -> bool:
        return self.raw["verdict"] == "met"

    @property
    def gains(self) -> dict[str, float] | None:
        """The certificate's gains (for an infeasible spec the best found), or None."""
        cert = self.raw["result"]["certificate"]
        return None if cert is None else cert["gains"]


def _axis_values(axis: dict[str, Any]) -> np.ndarray:
    """An axis's values exactly as the library computes them (lo + (hi - lo)·i/(n - 1), the
    last one hi)."""
    lo, hi, n = axis["lo"], axis["hi"], axis["n"]
    if n == 1:
        return np.array([lo])
    return np.array([hi if i == n - 1 else lo + (hi - lo) * (i / (n - 1)) for i in range(n)])


class SweepResult:
    """A map over a (Kp, Kd[, Ki]) grid and model parameters: `value[..., p2, p1, ki, kd, kp]`
    (the parameter axes in reverse order in front; NaN unless `status` is ok) and `status` of
    the same shape, with the axes `kp`, `kd`, `ki` and `params` ({name: values}); `settled_at`
    [s] where a max-Lyapunov run came to rest and was finished from its linearisation (NaN
    where it ran every step)."""

    def __init__(self, settings: dict[str, Any], points: list[dict[str, Any]]):
        self.settings = settings
        self.points = points
        grid = settings["grid"]

        n_kp, n_kd = grid["kp"]["n"], grid["kd"]["n"]
        n_ki = grid["ki"]["n"] if grid.get("ki") else 1
        # The axes as the points have them (row-major: Kp fastest, then Kd, then Ki).
        self.kp = np.array([p["kp"] for p in points[:n_kp]])
        self.kd = np.array([p["kd"] for p in points[: n_kp * n_kd : n_kp]])
        self.ki = np.array([p["ki"] for p in points[:: n_kp * n_kd]][:n_ki])
        self.params = {a["name"]: _axis_values(a) for a in grid.get("params", [])}
        shape = (
            *(len(v) for v in reversed(self.params.values())),
            len(self.ki),
            len(self.kd),
            len(self.kp),
        )
        value = np.full(len(points), np.nan)
        settled_at = np.full(len(points), np.nan)
        status = np.empty(len(points), dtype=object)
        for i, p in enumerate(points):
            if p["value"] is not None:
                value[i] = p["value"]
            if p.get("settled_at") is not None:
                settled_at[i] = p["settled_at"]
            status[i] = p["status"]
        self.value = value.reshape(shape)
        self.settled_at = settled_at.reshape(shape)
        self.status = status.reshape(shape)

    def __repr__(self) -> str:
        return f"SweepResult({self.settings['metric']}, shape {self.value.shape})"
