"""Parameter declarations and the vehicle parameter files.

A model's parameters stay symbolic in the IR; each declaration says where its value comes from in
a TOML file (`key`, and `index` for a component of an array such as `I1 = [Ixx, Iyy, Izz]`), its
unit, and its kind, which decides how a reader validates it (mass and inertia must be positive,
an inertia triple must satisfy the triangle inequality).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

KINDS = ("mass", "inertia", "length", "gravity", "other")


@dataclass(frozen=True)
class Param:
    """One scalar parameter of a model."""

    name: str
    unit: str
    kind: str = "other"
    key: str | None = None
    index: int | None = None
    default: float | None = None
    description: str = ""

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"parameter {self.name}: unknown kind {self.kind!r}")

    @property
    def toml_key(self) -> str:
        return self.key if self.key is not None else self.name


def _triple(key: str, unit: str, kind: str, what: str) -> list[Param]:
    axes = ("xx", "yy", "zz")
    return [
        Param(f"{key}_{ax}", unit, kind, key=key, index=i, description=f"{what}, {ax}")
        for i, ax in enumerate(axes)
    ]


# The vehicle schema (docs/src/conventions.md). Every vehicle model declares all of them, in
# this order, so that any vehicle parameter file runs with any vehicle model; a model that does
# not use a parameter marks it "used": false in its IR.
VEHICLE_PARAMS: list[Param] = [
    Param("m1", "kg", "mass", description="base mass (body + person)"),
    Param("m2", "kg", "mass", description="pendulum mass"),
    Param("g", "m/s^2", "gravity", description="gravitational acceleration"),
    Param("a", "m", "length", description="base centroid height"),
    Param("b", "m", "length", description="pendulum centroid distance from the hinge (l)"),
    Param("c", "m", "length", description="track width"),
    *_triple("I1", "kg m^2", "inertia", "base inertia about its centroid"),
    *_triple("I2", "kg m^2", "inertia", "pendulum inertia about its centroid"),
    Param("R", "m", "length", description="wheel radius"),
    Param("m_w", "kg", "mass", description="mass of one wheel"),
    Param("J_a", "kg m^2", "inertia", description="axial inertia of one wheel"),
    Param("J_d", "kg m^2", "inertia", description="diametral inertia of one wheel"),
]


class ParamFileError(ValueError):
    """A parameter file that cannot be used; the message names the file and the field."""


def load_values(path: Path, params: list[Param]) -> list[float]:
    """Read a TOML parameter file into values in the order of `params`, validating every field."""
    try:
        table = tomllib.loads(path.read_text())
    except OSError as err:
        raise ParamFileError(f"{path}: cannot read: {err.strerror}") from err
    except tomllib.TOMLDecodeError as err:
        raise ParamFileError(f"{path}: malformed TOML: {err}") from err
    known = {p.toml_key for p in params}
    for key in table:
        if key not in known:
            raise ParamFileError(f"{path}: unknown key `{key}`")
    values = []
    for p in params:
        if p.toml_key not in table:
            raise ParamFileError(f"{path}: missing key `{p.toml_key}` ({p.description})")
        raw = table[p.toml_key]
        if p.index is not None:
            if not isinstance(raw, list) or len(raw) != 3:
                raise ParamFileError(f"{path}: `{p.toml_key}` must be an array of 3 numbers")
            raw = raw[p.index]
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            raise ParamFileError(f"{path}: `{p.name}` must be a number, got {raw!r}")
        value = float(raw)
        if not math.isfinite(value):
            raise ParamFileError(f"{path}: `{p.name}` must be finite, got {value}")
        if p.kind in ("mass", "inertia", "gravity") and value <= 0.0:
            raise ParamFileError(f"{path}: `{p.name}` must be positive, got {value}")
        values.append(value)
    return values
