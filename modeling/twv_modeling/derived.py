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
    # ∂f/∂x in a form of the derivation's own (multibody: through the mass matrix's inverse),
    # with the sparsity of CasADi's ∂f/∂x; None: CasADi's differentiation of f.
    jac_x: ca.SX | None = None

    def jacobian_x(self) -> ca.SX:
        """∂f/∂x as the exports write it."""
        if self.jac_x is not None:
            return self.jac_x
        return ca.jacobian(self.expressions["f"], self.x)


def operations(fn: ca.Function) -> int:
    """The arithmetic operations of a CasADi function after CSE (its instructions less inputs,
    outputs and constants): the count exports are compared by."""
    skip = {ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST}
    return sum(fn.instruction_id(k) not in skip for k in range(fn.n_instructions()))
