"""The analyses: keyword arguments → the library's settings → the Rust job → a result object.
Each returns exactly what `twv <job> --json` prints for the same inputs (as `.raw`)."""

from __future__ import annotations

import json
import math
import os
import pathlib
from concurrent.futures import Executor
from typing import Any

from . import _native
from ._arrays import vector
from ._model import Model
from ._native import InputError
from ._results import (
    LinearResult,
    Result,
    RideResult,
    SimResult,
    SpectrumResult,
    SweepResult,
    TuneResult,
)
from ._settings import integrator, pid, run_settings


def _non_finite(value, path: str) -> str | None:
    """The path of the first NaN or infinity in a settings tree."""
    if isinstance(value, float) and not math.isfinite(value):
        return f"{path} = {value}"
    items = (
        value.items()
        if isinstance(value, dict)
        else (enumerate(value) if isinstance(value, list) else ())
    )
    for key, item in items:
        found = _non_finite(item, f"{path}.{key}" if path else str(key))
        if found:
            return found
    return None


def _settings_text(settings: dict[str, Any]) -> str:
    bad = _non_finite(settings, "")
    if bad:
        raise InputError(f"{bad} is not finite")
    return json.dumps(settings)


def _run(job: str, model: Model, settings: dict[str, Any]):
    if not isinstance(model, Model):
        raise InputError(f"model: a twv.Model, not {type(model).__name__}")
    return _native.run(job, model._native, _settings_text(settings))


def default_settings(job: str) -> dict[str, Any]:
    """The library's default settings of `job` (spectrum, simulate, linear, tune, audit)."""
    return json.loads(_native.default_settings(job))


def lyapunov_spectrum(
    model: Model,
    x0,
    *,
    u=None,
    controller: dict[str, Any] | None = None,
    preset: str | None = None,
    qr_interval: float = 0.1,
    iterations: int = 100,
    transient: float = 0.0,
    integrator_kind: str = "rk4",
    h: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    tangent_error_control: bool = False,
    k: int | None = None,
    seed: int | None = None,
    zero_floor: float | None = None,
    running: bool = True,
) -> SpectrumResult:
    """Lyapunov spectrum (Benettin–QR) from x0 [SI, rad]: re-orthonormalised every qr_interval
    T [s] over `iterations` intervals after `transient` [s]; RK4 (h, default 1e-3 s) or
    Dormand–Prince; k exponents (default all); identity basis or a random one from `seed`.
    `preset="paper"` is the study's T = 0.1 s, K = 100, RK4 h = 1e-3 (the defaults). With a
    `controller` (see `twv.pid`) the spectrum is the closed loop's."""
    if preset not in (None, "paper"):
        raise InputError(f"preset: `{preset}`; the only preset is 'paper'")
    settings = {
        "x0": vector("x0", x0),
        "u": None if u is None else vector("u", u),
        "controller": controller,
        "lyapunov": {
            "t_sample": float(qr_interval),
            "iterations": int(iterations),
            "transient": float(transient),
            "integrator": integrator(integrator_kind, h, rtol, atol, tangent_error_control),
            "basis": {"kind": "identity"} if seed is None else {"kind": "random", "seed": seed},
            "zero_floor": zero_floor,
            "record_running": bool(running),
        },
        "exponents": k,
    }
    raw, csv = _run("spectrum", model, settings)
    return SpectrumResult(json.loads(raw), csv)


def simulate(
    model: Model,
    x0=None,
    *,
    phi0: float = 0.1,
    controller: dict[str, Any] | None = None,
    t_end: float = 10.0,
    sample: float = 0.01,
    integrator_kind: str = "rk4",
    h: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    fall_angle: float | None = math.pi / 2,
    title: str = "tilt",
    scenario: str = "tilt",
) -> SimResult:
    """A closed-loop run under `controller` (default the study's PD, `twv.pid()`) from x0, or
    from rest with the pitch at phi0 [rad]; t_end and sample [s]; stops when |Φ| passes
    fall_angle [rad] (None: runs on)."""
    settings = {
        "title": title,
        "scenario": scenario,
        "controller": controller if controller is not None else pid(),
        "run": run_settings(t_end, sample, integrator_kind, h, rtol, atol, fall_angle),
        "x0": None if x0 is None else vector("x0", x0),
        "phi0": float(phi0),
    }
    raw, csv = _run("simulate", model, settings)
    return SimResult(json.loads(raw), csv)


def ride(
    model: Model,
    x0=None,
    *,
    speed: float | None = None,
    perturb: dict[str, float] | None = None,
    u=None,
    watch: str = "phi",
    t_end: float = 10.0,
    sample: float = 0.01,
    integrator_kind: str = "rk4",
    h: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    fall_angle: float | None = math.pi / 2,
) -> RideResult:
    """An uncontrolled run under constant inputs `u` from x0, or from the model's steady motion
    at `speed` [m/s] (the bicycle's straight running), plus `perturb` ({state: push}); the run
    stops when |watch| passes fall_angle. `verdict`: recovered (the watched state's last 10 %
    within a tenth of its peak), not_recovered, fell or undisturbed."""
    settings = {
        "x0": None if x0 is None else vector("x0", x0),
        "speed": None if speed is None else float(speed),
        "perturb": {str(k): float(v) for k, v in (perturb or {}).items()},
        "u": None if u is None else vector("u", u),
        "watch": watch,
        "run": run_settings(t_end, sample, integrator_kind, h, rtol, atol, fall_angle),
    }
    raw, csv = _run("ride", model, settings)
    return RideResult(json.loads(raw), csv)


def disturb(
    model: Model,
    direction: str = "forward",
    tilt: float = 0.1,
    **options,
) -> SimResult:
    """The study's Figs. 5 and 6: recovery from a forward or backward tilt of `tilt` [rad]
    (options as `simulate`)."""
    figure = {"forward": "Fig. 5", "backward": "Fig. 6"}.get(direction)
    if figure is None:
        raise InputError(f"direction: `{direction}`; use forward or backward")
    if not (math.isfinite(tilt) and tilt > 0):
        raise InputError(f"tilt: {tilt} must be a finite angle > 0 rad (direction gives the sign)")
    sign = 1.0 if direction == "forward" else -1.0
    return simulate(
        model,
        phi0=sign * tilt,
        title=f"{figure}: {direction} tilt of {tilt} rad",
        scenario=f"{direction} tilt",
        **options,
    )


def linearize(
    model: Model,
    at="upright",
    *,
    gains: tuple[float, float, float] = (3860.0, 0.0, 1980.0),
    lag: float = 0.0,
    delay: float = 0.0,
    lqr_q: float = 1.0,
    lqr_r: float = 1e-4,
    allow_non_equilibrium: bool = False,
) -> LinearResult:
    """Linearisation at `at` (`upright`, `hanging` or a state): open-loop modes, the PID pitch
    loop with gains (Kp, Ki, Kd) through an actuator lag and delay [s] — poles and gain, phase,
    delay and disk margins — and the LQR with weights Q = lqr_q·I, R = lqr_r·I."""
    where = at if at in ("upright", "hanging") else {"state": vector("at", at)}
    kp, ki, kd = gains
    settings = {
        "at": where,
        "gains": {"kp": float(kp), "ki": float(ki), "kd": float(kd)},
        "loop_options": {"lag": float(lag), "delay": float(delay)},
        "lqr_q": float(lqr_q),
        "lqr_r": float(lqr_r),
        "allow_non_equilibrium": bool(allow_non_equilibrium),
    }
    raw, _ = _run("linear", model, settings)
    return LinearResult(json.loads(raw))


def margins(model: Model, gains=(3860.0, 0.0, 1980.0), **options) -> dict[str, Any] | None:
    """The pitch loop's gain, phase, delay and disk margins (None for an unstable loop)."""
    return linearize(model, gains=gains, **options).margins


def lqr(model: Model, q: float = 1.0, r: float = 1e-4) -> dict[str, Any]:
    """The LQR of the cart–pendulum part (phi, x, w_y, v_x): gain K, Riccati P, poles."""
    return linearize(model, lqr_q=q, lqr_r=r).lqr


def tune(
    model: Model,
    spec: str = "dpm>=45",
    *,
    pid_gains: bool = False,
    objective: str | None = None,
    target: tuple[float, float] | None = None,
    lag: float = 0.0,
    delay: float = 0.0,
    tilt: float = 0.1,
) -> TuneResult:
    """Gains meeting `spec` (e.g. "dpm>=60,dgm>=6dB,ms<=1.6,force<=500") by convex-concave
    QPs (Clarabel): a PD (or PID with pid_gains=True); objective `min_gain` (PD default),
    `max_integral` (PID default), `max_proportional`, or closest to target (Kp, Kd); checked
    independently and on the nonlinear model after a tilt [rad]."""
    options: dict[str, Any] = {
        "pid": bool(pid_gains),
        "loop_options": {"lag": float(lag), "delay": float(delay)},
        "effort_tilt": float(tilt),
    }
    if target is not None:
        t = {"kp": float(target[0]), "ki": 0.0, "kd": float(target[1])}
        options["target"] = t
        options["objective"] = {"target": t}
    elif objective is not None:
        options["objective"] = objective
    raw, _ = _run("tune", model, {"spec": spec, "options": options, "tilt": float(tilt)})
    return TuneResult(json.loads(raw))


def audit(
    model: Model,
    *,
    hand: str | os.PathLike | None = None,
    hand_text: str | None = None,
    samples: int = 200,
    seed: int = 2016,
    tolerance: float = 1e-11,
    param_spread: float = 2.0,
):
    """The audit of a vehicle's derived equations. Without `hand`: against twv's independent
    hand model and physics (energy, momenta, symmetry). With `hand` (a hand file, README "Your
    own hand model") or `hand_text` (its TOML text): `model` against your hand model, term by
    term, each disagreeing entry with `difference` = hand - derived, simplified. `passed` says
    whether every check held. `param_spread` (hand files only): every second sample varies each
    parameter by a factor in [1/spread, spread], so a term that vanishes for this vehicle's
    values still shows."""
    settings = {"samples": int(samples), "seed": int(seed), "tolerance": float(tolerance)}
    if hand is not None and hand_text is not None:
        raise InputError("audit: give hand (a file) or hand_text, not both")
    if hand is not None:
        path = pathlib.Path(hand)
        try:
            hand_text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            raise InputError(f"cannot read {path}: {e}") from None
        origin = str(path)
    else:
        origin = "hand file"
    if hand_text is None:
        raw, _ = _run("audit", model, settings)
    else:
        settings["param_spread"] = float(param_spread)
        job = {"hand": str(hand_text), "origin": origin, "audit": settings}
        raw, _ = _run("audit_hand", model, job)
    return Result(json.loads(raw))


def steady_motion(model: Model, speeds=(0.0, 10.0, 0.01)):
    """The eigenvalues of the lean and steer about straight running against speed (models whose
    IR describes a steady motion: "whipple"), `speeds` = (lo, hi, step) in m/s; `raw` holds
    `points` (speed, eigenvalues, spectral_abscissa), `stable_ranges` and the `verdict`."""
    lo, hi, step = speeds
    raw, _ = _run("steady", model, {"lo": float(lo), "hi": float(hi), "step": float(step)})
    return Result(json.loads(raw))


def _axis(name: str, value) -> dict[str, Any] | None:
    if value is None:
        return None
    lo, hi, n = value
    return {"lo": float(lo), "hi": float(hi), "n": int(n)}


def sweep(
    model: Model,
    kp=(0.0, 8000.0, 100),
    kd=(0.0, 4000.0, 100),
    ki=None,
    *,
    metric: str = "max-lyapunov",
    tilt: float = 0.1,
    x0=None,
    controller: dict[str, Any] | None = None,
    params: dict[str, Any] | None = None,
    executor: Executor | None = None,
    shards: int | None = None,
    full_horizon: bool = False,
) -> SweepResult:
    """A stability map over a (Kp, Kd[, Ki]) grid, each axis (lo, hi, n), and over model
    parameters, `params={"m2": (4, 20, 17), ...}` by the IR's parameter names (each slower than
    the gains and the ones before it): `max-lyapunov`, `spectral-abscissa` or `settling-time`,
    from a tilt [rad] under the controller's other settings. Runs in parallel in Rust; with an
    `executor` (a concurrent.futures pool, a dask.distributed Client) its shards run there
    instead and are joined in index order. `max-lyapunov` finishes a loop that has come to
    rest from its linearisation there (the settled tail: λ1 within `twv.SETTLED_TAIL_TOLERANCE` of
    the full run, `settled_at` says when); `full_horizon=True` steps every point to the end."""
    grid: dict[str, Any] = {"kp": _axis("kp", kp), "kd": _axis("kd", kd), "ki": _axis("ki", ki)}
    if params:
        grid["params"] = [{"name": str(k), **_axis(str(k), v)} for k, v in params.items()]
    settings: dict[str, Any] = {
        "grid": grid,
        "metric": metric,
        "tilt": float(tilt),
        "x0": None if x0 is None else vector("x0", x0),
    }
    if controller is not None:
        settings["controller"] = controller
    if full_horizon:
        settings["metric_settings"] = {"settle_distance": None}
    text = _settings_text(settings)
    if executor is None:
        raw, _ = _native.run("sweep", model._native, text)
        return SweepResult(settings, json.loads(raw))
    total = _native.sweep_len(model._native, text)
    n = shards or 4 * getattr(executor, "_max_workers", 2)
    bounds = [total * i // n for i in range(n + 1)]
    futures = [
        executor.submit(_sweep_shard, model, text, lo, hi)
        for lo, hi in zip(bounds, bounds[1:], strict=False)
        if hi > lo
    ]
    points = [p for f in futures for p in json.loads(f.result())]
    return SweepResult(settings, points)


def _sweep_shard(model: Model, settings: str, start: int, stop: int) -> str:
    """One shard of a sweep, in whatever process the executor chose."""
    return _native.sweep_range(model._native, settings, start, stop)


def report(out, *, params=None, quick: bool = False) -> Result:
    """The study's report into the folder `out` (index.html, figures, data, results.json), from
    the bundled vehicle or a parameter file; `passed` says whether every check held."""
    import os

    raw = _native.report(
        os.fspath(out), params=None if params is None else os.fspath(params), quick=quick
    )
    return Result(json.loads(raw))
