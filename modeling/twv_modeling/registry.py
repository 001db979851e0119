"""Build a shipped model (or a user's model file) into a DerivedModel with its default values."""

from __future__ import annotations

from pathlib import Path

from .derived import DerivedModel
from .explicit import load_model_file
from .models import EXPLICIT, EXPLICIT_DIR, OTHER_MULTIBODY, SHIPPED, VEHICLES
from .models import vehicles as vehicle_models
from .models import whipple as whipple_model
from .multibody import derive
from .params import Param, load_values

REPO_ROOT = Path(__file__).resolve().parents[2]
VEHICLES_DIR = REPO_ROOT / "vehicles"


class UnknownModelError(ValueError):
    pass


def build(name: str) -> DerivedModel:
    """Derive a shipped model; vehicle defaults come from its reference parameter file."""
    if name in VEHICLES:
        P, p_vec = vehicle_models.symbols()
        model = derive(vehicle_models.BUILDERS[name](P), P, p_vec)
        source = vehicle_models.PARAMS_SOURCE[name]
        return with_defaults_from(model, VEHICLES_DIR / source, f"vehicles/{source}")
    if name in OTHER_MULTIBODY:
        P, p_vec = whipple_model.symbols()
        model = derive(whipple_model.whipple(P), P, p_vec)
        source = OTHER_MULTIBODY[name]
        return with_defaults_from(model, VEHICLES_DIR / source, f"vehicles/{source}")
    if name in EXPLICIT:
        return load_model_file(EXPLICIT_DIR / f"{name}.py")
    raise UnknownModelError(f"unknown model `{name}` (shipped: {', '.join(SHIPPED)})")


def with_defaults_from(model: DerivedModel, path: Path, label: str) -> DerivedModel:
    """`model` with its parameter defaults read from the vehicle file `path` (named `label`)."""
    values = load_values(path, model.params)
    model.params = [_with_default(p, v) for p, v in zip(model.params, values, strict=True)]
    model.params_source = label
    return model


def build_file(path: Path) -> DerivedModel:
    return load_model_file(path)


def _with_default(p: Param, value: float) -> Param:
    return Param(p.name, p.unit, p.kind, p.key, p.index, value, p.description)
