"""twv: two-wheeled vehicle dynamics, from bodies and joints to spectra, maps and tuned gains.

    import twv
    m = twv.Model("vehicle8", params={"m2": 10.0})
    s = twv.lyapunov(m, [0.1, 0, 0, 0, 0, 0, 0, 0], preset="paper")
    r = twv.disturb(m, direction="forward", tilt=0.1)
    g = twv.tune(m, spec="dpm>=60")
    lin = twv.linearize(m, gains=g)            # tune's result is accepted wherever gains are
    A, B, C, D = lin.state_space()
    mp = twv.sweep(m, kp="0:8000:50", kd="0:4000:50")
    bike = twv.steady(twv.Model("whipple"), speed="0:10:0.01")   # bike.weave_speed, .capsize_speed

Every job of the library's registry is a function here with the same name as the CLI's
subcommand and the JSON API's job, its options as keyword arguments with the library's own
defaults (`help(twv.simulate)`); `twv.settings(job, **options)` shows what a call would run.
The derivation (CasADi) is `twv.modeling`; `twv.derive` turns a description into a Model. The
numerics run in Rust (twv._native); results equal the CLI's JSON for the same inputs. Units are
SI (kg, m, s, N, rad).
"""

from ._gains import Gains
from ._jobs import FUNCTIONS, JOBS, build_info, default_settings, report, settings
from ._model import Model, derive
from ._native import (
    SETTLED_TAIL_TOLERANCE,
    InputError,
    ModelError,
    NumericalError,
    TwvError,
    shipped_models,
)
from ._results import (
    ExponentResult,
    LinearResult,
    Result,
    RideResult,
    SimResult,
    SpectrumResult,
    SteadyResult,
    SweepResult,
    TuneResult,
)

globals().update(FUNCTIONS)
# The jobs' older names, as documented aliases (`twv.lyapunov_spectrum` is `twv.lyapunov`).
globals().update({alias: FUNCTIONS[name] for name, job in JOBS.items() for alias in job["aliases"]})


def margins(model, **options):
    """The pitch loop's gain, phase, delay and disk margins (None for an unstable loop): the
    `margins` of `twv.linearize(model, **options)`."""
    return FUNCTIONS["linearize"](model, **options).margins


def lqr(model, **options):
    """The LQR of the cart–pendulum part (gain `k`, Riccati `p`, `poles`): the `lqr` of
    `twv.linearize(model, **options)` (weights `lqr_q`, `lqr_r`)."""
    return FUNCTIONS["linearize"](model, **options).lqr


__all__ = [
    "SETTLED_TAIL_TOLERANCE",
    "ExponentResult",
    "Gains",
    "InputError",
    "JOBS",
    "LinearResult",
    "Model",
    "ModelError",
    "NumericalError",
    "Result",
    "RideResult",
    "SimResult",
    "SpectrumResult",
    "SteadyResult",
    "SweepResult",
    "TuneResult",
    "TwvError",
    "build_info",
    "default_settings",
    "derive",
    "lqr",
    "margins",
    "modeling",
    "report",
    "settings",
    "shipped_models",
    *FUNCTIONS,
]


def __getattr__(name: str):
    # twv.modeling imports CasADi (slow); only when asked for.
    if name == "modeling":
        import importlib

        return importlib.import_module("twv.modeling")
    raise AttributeError(f"module 'twv' has no attribute {name!r}")
