"""Explicit-ODE models: a user writes x_dot = f(x, u, p) directly as CasADi expressions.

A model file is a Python file with a function `model()` returning an `ExplicitModel`:

    from twv_modeling.explicit import ExplicitModel
    from twv_modeling.params import Param

    def model():
        m = ExplicitModel("lorenz", states=[("x", "1"), ("y", "1"), ("z", "1")],
                          params=[Param("sigma", "1", default=10.0), ...])
        x, y, z = m.x_parts
        sigma, rho, beta = m.p_parts
        m.rhs = [sigma * (y - x), x * (rho - z) - y, x * y - beta * z]
        return m
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import casadi as ca

from .derived import DerivedModel, Signal
from .params import Param


class ExplicitModelError(ValueError):
    """A model file that does not define a usable explicit model."""


class ExplicitModel:
    """States, inputs and parameters as CasADi symbols; set `rhs` (and optionally `energy`)."""

    def __init__(self, name: str, states, inputs=(), params=(), description: str = ""):
        self.name = name
        self.description = description
        self.states = [Signal(*s) for s in states]
        self.inputs = [Signal(*s) for s in inputs]
        self.params = list(params)
        self.x_parts = [ca.SX.sym(s.name) for s in self.states]
        self.u_parts = [ca.SX.sym(s.name) for s in self.inputs]
        self.p_parts = [ca.SX.sym(p.name) for p in self.params]
        self.rhs = None
        self.energy = None

    def derive(self) -> DerivedModel:
        if self.rhs is None or len(self.rhs) != len(self.states):
            raise ExplicitModelError(
                f"model {self.name}: rhs must hold one expression per state ({len(self.states)})"
            )
        for p in self.params:
            if p.default is None:
                raise ExplicitModelError(f"model {self.name}: parameter {p.name} needs a default")
        x = ca.vertcat(*self.x_parts) if self.x_parts else ca.SX(0, 1)
        u = ca.vertcat(*self.u_parts) if self.u_parts else ca.SX(0, 1)
        p = ca.vertcat(*self.p_parts) if self.p_parts else ca.SX(0, 1)
        expressions = {"f": ca.vertcat(*[ca.SX(e) for e in self.rhs])}
        if self.energy is not None:
            expressions["energy"] = ca.SX(self.energy)
        return DerivedModel(
            self.name,
            "explicit",
            self.description,
            self.states,
            self.inputs,
            self.params,
            x,
            u,
            p,
            expressions,
            params_source="defaults",
        )


def load_model_file(path: Path) -> DerivedModel:
    """Import a user's model file and derive its model; errors name the file."""
    if not path.is_file():
        raise ExplicitModelError(f"{path}: no such model file")
    spec = importlib.util.spec_from_file_location(f"twv_user_model_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    try:
        sys.modules[spec.name] = module
        spec.loader.exec_module(module)
        build = getattr(module, "model", None)
        if build is None:
            raise ExplicitModelError(f"{path}: defines no function `model()`")
        built = build()
    except ExplicitModelError:
        raise
    except Exception as err:  # a user's file may fail in any way; report it as theirs
        raise ExplicitModelError(f"{path}: {type(err).__name__}: {err}") from err
    finally:
        sys.modules.pop(spec.name, None)
    if not isinstance(built, ExplicitModel):
        raise ExplicitModelError(f"{path}: model() must return an ExplicitModel")
    return built.derive()


__all__ = ["ExplicitModel", "ExplicitModelError", "Param", "load_model_file"]
