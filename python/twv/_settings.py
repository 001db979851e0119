"""Keyword arguments to the library's settings (the serde schema of twv_analysis::api), with
the CLI's defaults; the Rust side validates every value and names the field it refuses."""

from __future__ import annotations

import math
from typing import Any

from ._native import InputError


def integrator(
    kind: str = "rk4",
    h: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    tangent_error_control: bool = False,
) -> dict[str, Any]:
    """RK4 with step h (default 1e-3 s), or Dormand–Prince 5(4) with rtol (1e-9) and atol
    (1e-12), h its initial step."""
    if kind == "rk4":
        return {"kind": "rk4", "h": 1e-3 if h is None else float(h)}
    if kind == "dopri":
        return {
            "kind": "dopri",
            "rtol": 1e-9 if rtol is None else float(rtol),
            "atol": 1e-12 if atol is None else float(atol),
            "tangent_error_control": bool(tangent_error_control),
            "h_init": None if h is None else float(h),
        }
    raise InputError(f"integrator: `{kind}`; use rk4 or dopri")


def setpoint_settings(value) -> dict[str, Any]:
    """`study` (0.03·sin Φ), `zero`, ("sine", A) or a constant angle [rad]."""
    if value == "study":
        return {"kind": "sine", "amplitude": 0.03}
    if value == "zero":
        return {"kind": "zero"}
    if isinstance(value, tuple) and len(value) == 2 and value[0] == "sine":
        return {"kind": "sine", "amplitude": float(value[1])}
    if isinstance(value, (int, float)):
        return {"kind": "constant", "value": float(value)}
    raise InputError(f"setpoint: {value!r}; use 'study', 'zero', ('sine', A) or an angle")


def _profile(value: float) -> dict[str, Any]:
    return {"points": [[0.0, float(value)]]}


def pid(
    kp: float = 3860.0,
    kd: float = 1980.0,
    ki: float = 0.0,
    *,
    setpoint: Any = "study",
    rate_filter: float | None = None,
    f_max: float | None = None,
    anti_windup: str = "conditional",
    tracking_time: float | None = None,
    v_loop: tuple[float, float] | None = None,
    v_ref: float = 0.0,
    lean_max: float | None = None,
    yaw_kp: float | None = None,
    yaw_ref: float = 0.0,
) -> dict[str, Any]:
    """The controller: F = Kp·e + Ki·∫e + Kd·Φ̇ on the pitch [N/rad, N/(rad s), N s/rad] with
    the study's setpoint 0.03·sin Φ by default, an optional rate filter τ [s], force limit [N]
    with anti-windup (none, conditional, back_calculation with tracking_time [s]), a velocity
    loop (kp [rad per m/s], ki [rad per m]) to v_ref [m/s] and a yaw-rate loop."""
    if anti_windup == "back_calculation":
        aw = {
            "kind": "back_calculation",
            "tracking_time": 0.3 if tracking_time is None else float(tracking_time),
        }
    elif anti_windup in ("none", "conditional"):
        if tracking_time is not None:
            raise InputError("tracking_time: needs anti_windup='back_calculation'")
        aw = {"kind": anti_windup}
    else:
        raise InputError(f"anti_windup: `{anti_windup}`; use none, conditional, back_calculation")
    velocity = None
    if v_loop is not None:
        vkp, vki = v_loop
        velocity = {"kp": float(vkp), "ki": float(vki), "reference": _profile(v_ref)}
        if lean_max is not None:
            velocity["lean_max"] = float(lean_max)
    elif lean_max is not None or v_ref != 0.0:
        raise InputError("v_ref, lean_max: need the velocity loop (v_loop=(kp, ki))")
    yaw = None
    if yaw_kp is not None:
        yaw = {"kp": float(yaw_kp), "reference": _profile(yaw_ref)}
    elif yaw_ref != 0.0:
        raise InputError("yaw_ref: needs the yaw loop (yaw_kp=...)")
    return {
        "pitch": {
            "gains": {"kp": float(kp), "ki": float(ki), "kd": float(kd)},
            "setpoint": setpoint_settings(setpoint),
            "derivative_filter": rate_filter,
            "saturation": f_max,
            "anti_windup": aw,
        },
        "velocity": velocity,
        "yaw": yaw,
    }


def run_settings(
    t_end: float = 10.0,
    sample: float = 0.01,
    integrator_kind: str = "rk4",
    h: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    fall_angle: float | None = math.pi / 2,
) -> dict[str, Any]:
    """Length [s], output interval [s], integrator and fall angle [rad] (None: run on)."""
    return {
        "t_end": float(t_end),
        "sample": float(sample),
        "integrator": integrator(integrator_kind, h, rtol, atol),
        "fall_angle": None if fall_angle in (None, math.inf) else float(fall_angle),
    }
