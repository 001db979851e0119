"""Shared fixtures: each shipped vehicle model derived once, with numeric CasADi functions."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np
import pytest

from twv_modeling.models import VEHICLES
from twv_modeling.params import VEHICLE_PARAMS, load_values
from twv_modeling.registry import VEHICLES_DIR, build

PARAM_FILES = ("paper.toml", "segway.toml")


@dataclass
class Numeric:
    """A derived model with numeric functions of (x, u, p)."""

    model: object
    fns: dict

    def __call__(self, name, x, u, p):
        return np.array(self.fns[name](x, u, p)).squeeze()

    @property
    def nx(self):
        return self.model.x.numel()

    @property
    def nu(self):
        return self.model.u.numel()

    def state_index(self, name):
        return [s.name for s in self.model.states].index(name)


@functools.cache
def numeric(name: str) -> Numeric:
    m = build(name)
    args = [m.x, m.u, m.p]
    fns = {k: ca.Function(k, args, [e]) for k, e in m.expressions.items()}
    fns["jac_x"] = ca.Function("jac_x", args, [ca.jacobian(m.expressions["f"], m.x)])
    return Numeric(m, fns)


@functools.cache
def param_values(file: str) -> tuple[float, ...]:
    return tuple(load_values(VEHICLES_DIR / file, VEHICLE_PARAMS))


def param(values, name):
    return values[[p.name for p in VEHICLE_PARAMS].index(name)]


@pytest.fixture(params=VEHICLES)
def vehicle(request):
    return numeric(request.param)


@pytest.fixture(params=PARAM_FILES)
def params(request):
    return np.array(param_values(request.param))


def random_states(model: Numeric, n: int, seed: int = 7, scale: float = 2.0):
    """Random states with large angles and fast spins, and random inputs."""
    rng = np.random.default_rng(seed)
    xs = rng.uniform(-scale, scale, size=(n, model.nx))
    xs[:, 0] = rng.uniform(-np.pi, np.pi, size=n)  # pitch anywhere, not only near upright
    us = rng.uniform(-50.0, 50.0, size=(n, model.nu))
    return xs, us
