"""twv: two-wheeled vehicle dynamics, from bodies and joints to spectra, maps and tuned gains.

    import twv
    m = twv.Model("vehicle8", params={"m2": 10.0})
    s = twv.lyapunov_spectrum(m, [0.1, 0, 0, 0, 0, 0, 0, 0], preset="paper")
    r = twv.disturb(m, "forward", 0.1)
    g = twv.tune(m, "dpm>=60")
    mp = twv.sweep(m, kp=(0, 8000, 50), kd=(0, 4000, 50))
    bike = twv.steady_motion(twv.Model("whipple"), (0, 10, 0.01))   # weave/capsize speeds
    free = twv.ride(twv.Model("whipple"), speed=5.0, perturb={"w_phi": 0.05})  # nobody steers

The derivation (CasADi) is `twv.modeling`; `twv.derive` turns a description into a Model. The
numerics run in Rust (twv._native); results equal the CLI's JSON for the same inputs. Units are
SI (kg, m, s, N, rad).
"""

from ._jobs import (
    audit,
    default_settings,
    disturb,
    linearize,
    lqr,
    lyapunov_spectrum,
    margins,
    report,
    ride,
    simulate,
    steady_motion,
    sweep,
    tune,
)
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
    LinearResult,
    Result,
    RideResult,
    SimResult,
    SpectrumResult,
    SweepResult,
    TuneResult,
)
from ._settings import integrator, pid

__all__ = [
    "SETTLED_TAIL_TOLERANCE",
    "InputError",
    "LinearResult",
    "Model",
    "ModelError",
    "NumericalError",
    "Result",
    "RideResult",
    "SimResult",
    "SpectrumResult",
    "SweepResult",
    "TuneResult",
    "TwvError",
    "audit",
    "default_settings",
    "derive",
    "disturb",
    "integrator",
    "linearize",
    "lqr",
    "lyapunov_spectrum",
    "margins",
    "modeling",
    "pid",
    "report",
    "ride",
    "shipped_models",
    "simulate",
    "steady_motion",
    "sweep",
    "tune",
]


def __getattr__(name: str):
    # twv.modeling imports CasADi (slow); only when asked for.
    if name == "modeling":
        import importlib

        return importlib.import_module("twv.modeling")
    raise AttributeError(f"module 'twv' has no attribute {name!r}")
