"""Result objects: the job's JSON (exactly what `twv <job> --json` prints) as `.raw`, read as
data — NumPy arrays (complex where the values are eigenvalues, matrices in their natural
shape), named fields, units — with the summary `twv <job>` prints as their `repr`."""

from __future__ import annotations

import functools
import io
from typing import Any

import numpy as np

from ._gains import Gains


def _array(value: Any) -> Any:
    """A list of numbers (or a rectangular list of such lists) as an array; anything else as
    it is."""
    if isinstance(value, list) and value and all(isinstance(v, int | float) for v in value):
        return np.array(value, dtype=float)
    if isinstance(value, list) and value and all(isinstance(v, list) for v in value):
        try:
            a = np.array(value, dtype=float)
        except (TypeError, ValueError):
            return value
        return a
    return value


def _complex(pairs) -> np.ndarray:
    """[[re, im], …] (how the library writes complex numbers) as a complex array."""
    a = np.asarray(pairs, dtype=float).reshape(-1, 2)
    return a[:, 0] + 1j * a[:, 1]


def _csv(text: str | None) -> tuple[list[str], np.ndarray]:
    """The library's CSV (a header, then rows of numbers at full precision) as column names
    and a 2-D array."""
    if not text:
        return [], np.zeros((0, 0))
    header, _, body = text.partition("\n")
    columns = header.split(",")
    data = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2) if body.strip() else None
    return columns, (data if data is not None else np.zeros((0, len(columns))))


def _pandas():
    try:
        import pandas
    except ImportError:
        raise ImportError("to_pandas() needs pandas: pip install pandas") from None
    return pandas


class Result:
    """A job's result. `raw` is the JSON object; its keys are also attributes (lists of numbers
    as arrays); `summary` is what `twv <job>` prints; `negative` the message of a negative
    verdict (the CLI's exit status 3), None otherwise."""

    def __init__(self, raw: Any, csv: str | None, summary: str, negative: str | None, model):
        self.raw = raw
        self.csv = csv
        self.summary = summary
        self.negative = negative
        self._model = model

    def __getattr__(self, name: str):
        raw = self.__dict__.get("raw")
        if isinstance(raw, dict) and name in raw:
            return _array(raw[name])
        raise AttributeError(name)

    @property
    def ok(self) -> bool:
        """Whether the verdict is positive (or there is none to give)."""
        return self.negative is None

    def __repr__(self) -> str:
        text = self.summary.strip()
        if not text and isinstance(self.raw, dict):
            text = ", ".join(self.raw)
        body = "\n".join(f"  {line}" for line in text.splitlines())
        return f"{type(self).__name__}(\n{body}\n)"


class SpectrumResult(Result):
    """A Lyapunov spectrum: exponents λ1 ≥ … [1/s], batch-means stderr (1σ), Σλ, ⟨tr J⟩,
    Kaplan–Yorke dimension, the verdict, and the running estimates."""

    @functools.cached_property
    def _table(self) -> tuple[list[str], np.ndarray]:
        # Parsed when first asked for: most calls want the exponents only.
        return _csv(self.csv)

    @property
    def columns(self) -> list[str]:
        """The running estimates' columns: t, λ1, …, Σλ."""
        return self._table[0]

    @property
    def t(self) -> np.ndarray:
        """Time since the transient [s] of each running estimate."""
        data = self._table[1]
        return data[:, 0] if data.size else np.zeros(0)

    @property
    def running(self) -> np.ndarray:
        """Running exponents [1/s], one row per re-orthonormalisation."""
        data, k = self._table[1], len(self.raw["exponents"])
        return data[:, 1 : 1 + k] if data.size else np.zeros((0, k))

    @property
    def running_sum(self) -> np.ndarray:
        """Running Σλ [1/s]."""
        data = self._table[1]
        return data[:, 1 + len(self.raw["exponents"])] if data.size else np.zeros(0)

    @property
    def exponents(self) -> np.ndarray:
        """λ1 ≥ λ2 ≥ … [1/s]."""
        return np.array(self.raw["exponents"])

    @property
    def stderr(self) -> np.ndarray:
        """Batch-means standard error of each exponent (1σ) [1/s]."""
        return np.array(self.raw["stderr"])

    @property
    def classification(self) -> str:
        """`equilibrium`, `stable_fixed_point`, `neutral`, `chaotic`, `hyperchaotic` or
        `not_converged` (the text is `raw["classification"]["text"]`)."""
        return self.raw["classification"]["kind"]

    def to_pandas(self):
        """The running estimates: one row per re-orthonormalisation."""
        return _pandas().DataFrame(
            np.column_stack([self.t, self.running])
            if self.t.size
            else np.zeros((0, len(self.columns) - 1)),
            columns=self.columns[: 1 + self.running.shape[1]],
        )


class _SeriesResult(Result):
    """A result with a time series: `columns`, `data`, `series[name]`, `t` and `units[name]`."""

    def __init__(self, *args):
        super().__init__(*args)
        self.columns, self.data = _csv(self.csv)
        self.series = {c: self.data[:, i] for i, c in enumerate(self.columns)}
        self.t = self.series.get("t", np.zeros(0))
        units = {"t": "s"}
        if self._model is not None:
            units |= self._model.units
        given = self.raw.get("units") if isinstance(self.raw, dict) else None
        if given and len(given) == len(self.columns):
            units |= dict(zip(self.columns, given, strict=True))
        self.units = {c: units.get(c, "") for c in self.columns}
        """Each column's unit (SI; empty where the model gives none)."""

    def to_pandas(self):
        """The samples, one row per sample, one column per series."""
        return _pandas().DataFrame(self.data, columns=self.columns)


class SimResult(_SeriesResult):
    """A closed-loop run: the time series, metrics, how it ended and whether the pitch
    recovered."""

    @property
    def recovered(self) -> bool:
        return self.raw["recovery"] == "recovered"


class RideResult(_SeriesResult):
    """An uncontrolled run: the time series, how it ended and the verdict on the watched
    state."""

    @property
    def verdict(self) -> str:
        """`recovered`, `not_recovered`, `fell` or `undisturbed`."""
        return self.raw["verdict"]


class LinearResult(Result):
    """The linearisation: A and B, the open-loop modes, the PID pitch loop (poles, margins) and
    the LQR; `state_space()` gives (A, B, C, D), `to_control()` a python-control StateSpace."""

    @property
    def A(self) -> np.ndarray:
        """∂f/∂x at the operating point (nx × nx)."""
        return np.array(self.raw["a"], dtype=float)

    @property
    def B(self) -> np.ndarray:
        """∂f/∂u at the operating point (nx × nu)."""
        return np.array(self.raw["b"], dtype=float).reshape(len(self.raw["states"]), -1)

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, C, D) with every state an output: C = I, D = 0."""
        a, b = self.A, self.B
        return a, b, np.eye(a.shape[0]), np.zeros((a.shape[0], b.shape[1]))

    def to_control(self):
        """The linearisation as a `control.StateSpace` with named states, inputs and outputs
        (needs python-control: pip install control)."""
        try:
            import control
        except ImportError:
            raise ImportError("to_control() needs python-control: pip install control") from None
        a, b, c, d = self.state_space()
        states, inputs = self.raw["states"], self.raw["inputs"]
        return control.ss(a, b, c, d, states=states, inputs=inputs, outputs=states)

    @property
    def open_loop_eigenvalues(self) -> np.ndarray:
        """The open-loop eigenvalues [1/s], complex."""
        return _complex([m["eigenvalue"] for m in self.raw["open_loop"]])

    @property
    def loop_poles(self) -> np.ndarray:
        """The closed pitch loop's poles [1/s], complex (empty for a model without a pitch)."""
        pitch = self.raw["pitch"]
        return _complex(pitch["loop_poles"] if pitch else [])

    @property
    def margins(self) -> dict[str, Any] | None:
        """Gain, phase, delay and disk margins of a stable pitch loop (None otherwise)."""
        pitch = self.raw["pitch"]
        return pitch["margins"] if pitch else None

    @property
    def steer(self) -> dict[str, Any] | None:
        """The steer loop closed about the steady motion (`speed=`, `steer_gains=`): its `poles`
        (complex), whether it is `stable`, its `margins` at the steer torque (None when
        unstable) and every state's closed-loop `eigenvalues` (complex); None without a law."""
        st = self.raw.get("steer")
        if st is None:
            return None
        return {
            "law": st["law"],
            "modes": st["modes"],
            "poles": _complex(st["loop_poles"]["eigenvalues"]),
            "stable": st["loop_poles"]["stable"],
            "margins": st["margins"],
            "eigenvalues": _complex([m["eigenvalue"] for m in st["closed_loop"]]),
        }

    @property
    def lqr(self) -> dict[str, Any] | None:
        """The LQR of the cart–pendulum part: gain `k` and Riccati `p` as matrices, the
        closed-loop `poles` (complex)."""
        lqr = self.raw.get("lqr")
        if lqr is None:
            return None
        return {
            **lqr,
            "k": np.array(lqr["k"], dtype=float),
            "p": np.array(lqr["p"], dtype=float),
            "poles": _complex(lqr["closed_loop_eigenvalues"]),
        }


class SteadyResult(Result):
    """Eigenvalues of a steady motion's modes against speed: `speeds` [m/s], `eigenvalues`
    (complex, one row per speed), `spectral_abscissa`, the stable ranges and, where they are
    bounded by an oscillating pair and a real mode, `weave_speed` and `capsize_speed`."""

    @property
    def speeds(self) -> np.ndarray:
        return np.array([p["speed"] for p in self.raw["points"]])

    @property
    def eigenvalues(self) -> np.ndarray:
        """[speed, mode] complex eigenvalues [1/s]."""
        return np.array([_complex(p["eigenvalues"]) for p in self.raw["points"]])

    @property
    def spectral_abscissa(self) -> np.ndarray:
        return np.array([p["spectral_abscissa"] for p in self.raw["points"]])

    @property
    def weave_speed(self) -> float | None:
        return self.raw["weave_speed"]

    @property
    def capsize_speed(self) -> float | None:
        return self.raw["capsize_speed"]

    @property
    def stable_ranges(self) -> list[tuple[float, float]]:
        return [tuple(r) for r in self.raw["stable_ranges"]]

    def to_pandas(self):
        """One row per speed: the real and imaginary part of each eigenvalue."""
        ev = self.eigenvalues
        data = {"speed": self.speeds}
        for j in range(ev.shape[1] if ev.ndim == 2 else 0):
            data[f"re_{j + 1}"] = ev[:, j].real
            data[f"im_{j + 1}"] = ev[:, j].imag
        return _pandas().DataFrame(data)


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
    def gains(self) -> Gains | None:
        """The certificate's gains (for an infeasible spec the best found), or None; accepted as
        `gains=` by every job."""
        cert = self.raw["result"]["certificate"]
        return None if cert is None else Gains(**cert["gains"])


class SteerResult(Result):
    """A steer controller over speed (`twv.steer`): per speed the gains (tuned or given), the
    closed loop's eigenvalues and margins at the steer torque, the nonlinear check, and whether
    the spec was `met` there."""

    _GAINS = ("k_phi", "k_delta", "k_phi_dot", "k_delta_dot")

    @property
    def speeds(self) -> np.ndarray:
        return np.array([p["speed"] for p in self.raw["points"]])

    @property
    def gains(self) -> np.ndarray:
        """[speed, gain] in the order k_phi, k_delta, k_phi_dot, k_delta_dot (NaN where no
        stabilising gains were found)."""
        rows = []
        for p in self.raw["points"]:
            cert = p["certificate"]
            rows.append([np.nan] * 4 if cert is None else [cert["gains"][k] for k in self._GAINS])
        return np.array(rows, dtype=float).reshape(-1, 4)

    @property
    def met(self) -> np.ndarray:
        """Per speed: the certificate meets the spec and the push is recovered from."""
        return np.array([p["met"] for p in self.raw["points"]], dtype=bool)

    @property
    def closed_loop_eigenvalues(self) -> list[np.ndarray]:
        """Per speed, the steered loop's complex eigenvalues [1/s] (empty without gains)."""
        out = []
        for p in self.raw["points"]:
            cert = p["certificate"]
            ev = [] if cert is None else cert["analysis"]["closed_loop"]["eigenvalues"]
            out.append(_complex(ev))
        return out

    @property
    def open_loop_eigenvalues(self) -> list[np.ndarray]:
        """Per speed, the eigenvalues of the bicycle nobody steers [1/s]."""
        return [_complex(p["open_loop"]) for p in self.raw["points"]]

    def to_pandas(self):
        """One row per speed: the gains, whether met, the disk phase margin [deg]."""
        data = {"speed": self.speeds, "met": self.met}
        for j, name in enumerate(self._GAINS):
            data[name] = self.gains[:, j]
        data["disk_phase_margin_deg"] = [
            np.nan
            if p["certificate"] is None
            else p["certificate"]["analysis"]["margins"]["disk"]["phase_deg"]
            for p in self.raw["points"]
        ]
        return _pandas().DataFrame(data)


class ExponentResult(Result):
    """The closed loop's largest exponent over a short horizon: `value` [1/s], `resolution`
    [1/s] and the `verdict` (stable, unstable, undecided, fell, failed)."""

    @property
    def value(self) -> float | None:
        return self.raw["point"]["value"]

    @property
    def verdict(self) -> str:
        return self.raw["verdict"]


def _axis_values(axis: dict[str, Any]) -> np.ndarray:
    """An axis's values exactly as the library computes them (lo + (hi - lo)·i/(n - 1), the
    last one hi)."""
    lo, hi, n = axis["lo"], axis["hi"], axis["n"]
    if n == 1:
        return np.array([lo])
    return np.array([hi if i == n - 1 else lo + (hi - lo) * (i / (n - 1)) for i in range(n)])


class SteerMapResult(Result):
    """The steered loop's stability over speed × one steer gain (`twv.steer_map`), or at one
    speed over one steer gain × another (`against`): `speeds` [m/s], `values` of the gain,
    `against_values` of the second gain, `x` (the map's x axis: `against_values` or `speeds`),
    `abscissa` [value, x] (the closed loop's largest eigenvalue real part [1/s], NaN where not
    finite), `stable`, and nobody steering `weave_speed` and `capsize_speed` (or at one speed
    `unsteered_abscissa`; the JSON's own fields, read as every result's are)."""

    @property
    def x(self) -> np.ndarray:
        """The map's x axis: the second gain's values in a gain × gain map, else the speeds."""
        key = "against_values" if self.raw["against"] is not None else "speeds"
        return np.array(self.raw[key], dtype=float)

    @property
    def abscissa(self) -> np.ndarray:
        """[value, x]: max Re of the closed loop's eigenvalues [1/s]."""
        flat = [np.nan if a is None else a for a in self.raw["abscissa"]]
        return np.array(flat, dtype=float).reshape(len(self.raw["values"]), len(self.x))

    @property
    def stable(self) -> np.ndarray:
        """[value, x]: every closed-loop eigenvalue has Re < 0."""
        return self.abscissa < 0


class UncertaintyResult(Result):
    """Monte Carlo over a measured bicycle's parameter uncertainty (`twv.uncertainty`): per
    draw (one row each) the `draws` [draw, parameter] (columns `names`), `weave_speeds` and
    `capsize_speeds` [m/s] and `disk_phase_margins` [deg] (NaN where a draw has none), `stable`
    and `status`; the spreads are the JSON's `weave_speed`, `capsize_speed`,
    `disk_phase_margin_deg` ({count, mean, sd, min, p05, p50, p95, max})."""

    def _column(self, key: str) -> np.ndarray:
        return np.array(
            [np.nan if s[key] is None else s[key] for s in self.raw["samples"]], dtype=float
        )

    @property
    def draws(self) -> np.ndarray:
        """[draw, parameter]: the values drawn, in the order of `names`."""
        return np.array([s["params"] for s in self.raw["samples"]], dtype=float)

    @property
    def weave_speeds(self) -> np.ndarray:
        """Each draw's weave speed [m/s] (NaN: no self-stable band in the searched speeds)."""
        return self._column("weave_speed")

    @property
    def capsize_speeds(self) -> np.ndarray:
        """Each draw's capsize speed [m/s] (NaN: none)."""
        return self._column("capsize_speed")

    @property
    def disk_phase_margins(self) -> np.ndarray:
        """Each draw's disk phase margin at the steer torque [deg] (NaN: none)."""
        return self._column("disk_phase_margin_deg")

    @property
    def stable(self) -> np.ndarray:
        """Each draw's steered closed loop is stable at the check speed."""
        return np.array([s["stable"] for s in self.raw["samples"]], dtype=bool)

    def to_pandas(self):
        """One row per draw: the quantities, then the drawn values."""
        frame = _pandas().DataFrame(
            {
                "index": [s["index"] for s in self.raw["samples"]],
                "status": [s["status"] for s in self.raw["samples"]],
                "weave_speed": self.weave_speeds,
                "capsize_speed": self.capsize_speeds,
                "disk_phase_margin_deg": self.disk_phase_margins,
                "stable": self.stable,
            }
        )
        draws = self.draws
        for j, name in enumerate(self.raw["names"]):
            frame[name] = draws[:, j] if draws.size else []
        return frame


class SweepResult(Result):
    """A map over a (Kp, Kd[, Ki]) grid and model parameters: `value[..., p2, p1, ki, kd, kp]`
    (the parameter axes in reverse order in front; NaN unless `status` is ok) and `status` of
    the same shape, with the axes `kp`, `kd`, `ki` and `params` ({name: values}); `settled_at`
    [s] where a max-Lyapunov run came to rest and was finished from its linearisation (NaN
    where it ran every step)."""

    def __init__(self, raw, csv, summary, negative, model, settings=None):
        super().__init__(raw, csv, summary, negative, model)
        self.points = points = raw
        self.settings = settings if settings is not None else {}
        grid = self.settings.get("grid")
        if grid is None:
            grid = {
                "kp": {"n": len({p["kp"] for p in points})},
                "kd": {"n": len({p["kd"] for p in points})},
                "ki": None,
            }
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

    def to_pandas(self):
        """One row per grid point: index, kp, ki, kd, value, status, settled_at."""
        return _pandas().DataFrame(self.points)

    def __repr__(self) -> str:
        metric = self.settings.get("metric", "map")
        return f"SweepResult({metric}, shape {self.value.shape}: {self.summary.strip()})"


RESULTS: dict[str, type[Result]] = {
    "lyapunov": SpectrumResult,
    "simulate": SimResult,
    "disturb": SimResult,
    "ride": RideResult,
    "linearize": LinearResult,
    "steady": SteadyResult,
    "steer": SteerResult,
    "steer_map": SteerMapResult,
    "uncertainty": UncertaintyResult,
    "tune": TuneResult,
    "exponent": ExponentResult,
}
"""The result class of each job (the others: `Result`)."""
