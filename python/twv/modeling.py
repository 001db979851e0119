"""The derivation step, in the same namespace: bodies and joints (or explicit equations) to
CasADi expressions to the model IR. This is the `twv_modeling` package of the repository
(modeling/), imported here so that `import twv` is the whole pipeline."""

from __future__ import annotations

from pathlib import Path

try:
    import twv_modeling  # noqa: F401
except ImportError as err:  # pragma: no cover - an installation problem, said plainly
    raise ImportError(
        "twv.modeling needs the twv-modeling package (pip install ./modeling from the twv "
        "repository; it brings CasADi 3.8.2)"
    ) from err

from twv_modeling import ir as _ir
from twv_modeling import registry as _registry
from twv_modeling.derived import DerivedModel, Signal
from twv_modeling.explicit import ExplicitModel
from twv_modeling.kinematics import Body, PlanarJoint, RevoluteJoint
from twv_modeling.models import SHIPPED, vehicles
from twv_modeling.multibody import Constraint, ForceInput, MultibodySystem, TorqueInput
from twv_modeling.multibody import derive as _derive_multibody
from twv_modeling.params import VEHICLE_PARAMS, Param

__all__ = [
    "Body",
    "Constraint",
    "DerivedModel",
    "ExplicitModel",
    "ForceInput",
    "MultibodySystem",
    "Param",
    "PlanarJoint",
    "RevoluteJoint",
    "SHIPPED",
    "VEHICLE_PARAMS",
    "Signal",
    "TorqueInput",
    "derive_model",
    "ir_text",
    "vehicle_symbols",
    "vehicles",
]


def vehicle_symbols():
    """The vehicle parameter symbols (a dict by name) and their vector, to build a
    `MultibodySystem` from (see `vehicles.vehicle7(P)`)."""
    return vehicles.symbols()


def derive_model(system, symbols=None, defaults: str | Path | None = None) -> DerivedModel:
    """The derived equations of a shipped model's name, an `ExplicitModel`, a `MultibodySystem`
    (with `symbols` from `vehicle_symbols()`; parameter defaults from `defaults`, a vehicle
    TOML file, by default the repository's vehicles/paper.toml) or a `DerivedModel` itself."""
    if isinstance(system, DerivedModel):
        return system
    if isinstance(system, str):
        return _registry.build(system)
    if isinstance(system, ExplicitModel):
        return system.derive()
    if isinstance(system, MultibodySystem):
        P, p_vec = symbols if symbols is not None else vehicle_symbols()
        model = _derive_multibody(system, P, p_vec)
        path = Path(defaults) if defaults is not None else _registry.VEHICLES_DIR / "paper.toml"
        return _registry.with_defaults_from(model, path, str(path))
    raise TypeError(
        f"cannot derive a {type(system).__name__}: give a model name, an ExplicitModel, "
        "a MultibodySystem or a DerivedModel"
    )


def ir_text(system, symbols=None, defaults: str | Path | None = None) -> str:
    """The model IR (twv-ir/1 JSON text, deterministic) of what `derive_model` derives."""
    return _ir.dumps(_ir.build_ir(derive_model(system, symbols, defaults)))
