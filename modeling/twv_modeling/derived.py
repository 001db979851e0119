"""The result of a derivation: what the IR exporter needs, for any kind of model."""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from .params import Param


@dataclass(frozen=True)
class Signal:
    """A named state or input component."""

    name: str
    unit: str
    description: str = ""


@dataclass
class DerivedModel:
    """A model ready for export: symbols, declarations and the expressions of its functions.

    Every expression is a function of the state `x`, the input `u` and the parameters `p` only.
    `expressions` holds `f` and, for mechanical models, `M`, `Cp`, `F`, `Q`, `energy`, `momentum`;
    an explicit model may add `energy`.
    """

    name: str
    kind: str
    description: str
    states: list[Signal]
    inputs: list[Signal]
    params: list[Param]
    x: ca.SX
    u: ca.SX
    p: ca.SX
    expressions: dict[str, ca.SX]
    header: dict = field(default_factory=dict)
    params_source: str = ""
