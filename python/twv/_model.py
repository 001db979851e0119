"""`twv.Model`: a shipped model or a model IR with its parameters, evaluated on NumPy batches by
the Rust kernels; and `twv.derive`, from a description straight to a Model."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from . import _native
from ._arrays import rows
from ._native import InputError


class Model:
    """A model and its parameter values, resolved and checked as `twv --model/--ir/--params`.

    Model("vehicle8")                       shipped model; a vehicle gets its vehicle file
    Model(ir="my_model.json")               a model IR file (same bits as compiled code)
    Model(ir=ir_text_or_dict)               an IR in memory (what `derive` makes)
    params="file.toml" | {"m2": 10.0, "I2": [0.8, 0.8, 0.03]} | {"I2_zz": 0.03}
                                            a file, or values over the defaults, by file key
                                            or by component name (what `m.params` gives)
    runtime="jit" | "interpreter"           how a model without generated code runs: compiled
                                            to native code when loaded (default), or interpreted

    Units are SI (kg, m, s, N, rad) throughout.
    """

    def __init__(self, name: str | None = None, *, ir=None, params=None, runtime: str = "jit"):
        self._recipe = (name, ir, params, runtime)
        kwargs: dict[str, Any] = {"runtime": runtime}
        if ir is not None:
            if isinstance(ir, Mapping):
                kwargs["ir_json"] = json.dumps(ir)
            elif isinstance(ir, str) and ir.lstrip().startswith("{"):
                kwargs["ir_json"] = ir
            elif isinstance(ir, (str, os.PathLike)):
                kwargs["ir_file"] = os.fspath(ir)
            else:
                raise InputError("ir: a file path, IR JSON text or an IR dict")
        if params is not None:
            if isinstance(params, Mapping):
                kwargs["overrides"] = [
                    (str(k), [float(v) for v in np.atleast_1d(np.asarray(val, dtype=float))])
                    for k, val in params.items()
                ]
            elif isinstance(params, (str, os.PathLike)):
                kwargs["params_file"] = os.fspath(params)
            else:
                raise InputError("params: a TOML file path or a dict of values")
        self._native = _native.Model(name, **kwargs)

    def __reduce__(self):
        # Rebuilt from its recipe in another process (a process pool, a Dask worker).
        return (_rebuild, self._recipe)

    def __repr__(self) -> str:
        return f"Model({self.name!r}, {self.engine}, params from {self.params_origin})"

    @property
    def name(self) -> str:
        return self._native.name

    @property
    def states(self) -> list[str]:
        """State names, in order (the columns of x)."""
        return self._native.states

    @property
    def inputs(self) -> list[str]:
        """Input names, in order (the columns of u)."""
        return self._native.inputs

    @property
    def units(self) -> dict[str, str]:
        """The unit of every state, input and parameter by name (SI, from the IR)."""
        units = dict(zip(self.states, self._native.state_units, strict=True))
        units |= dict(zip(self.inputs, self._native.input_units, strict=True))
        units |= {name: unit for name, _, _, unit, _ in self._native.params}
        return units

    @property
    def nx(self) -> int:
        return len(self.states)

    @property
    def nu(self) -> int:
        return len(self.inputs)

    @property
    def engine(self) -> str:
        """`generated` (compiled kernels of a shipped model) or `interpreted` (an IR)."""
        return self._native.engine

    @property
    def params_origin(self) -> str:
        return self._native.params_origin

    @property
    def params(self) -> dict[str, float]:
        """Parameter values by IR name (`m2`, `I2_yy`), SI units; `Model(name, params=m.params)`
        takes them back (as it takes a file's keys, `I2 = [Ixx, Iyy, Izz]`)."""
        return {name: value for name, _, _, _, value in self._native.params}

    def _u(self, u, n: int):
        if u is None:
            return None
        a, _ = rows("u", u, self.nu)
        if a.shape[0] == 1 and n > 1:
            a = np.ascontiguousarray(np.broadcast_to(a, (n, self.nu)))
        return a

    def f(self, x, u=None) -> np.ndarray:
        """ẋ = f(x, u). x: (nx,) or (n, nx); u: (nu,) or (n, nu), default 0. Shape of x."""
        xs, single = rows("x", x, self.nx)
        out = self._native.f(xs, self._u(u, xs.shape[0]))
        return out[0] if single else out

    def jac_x(self, x, u=None) -> np.ndarray:
        """∂f/∂x: (nx, nx) for one state, (n, nx, nx) for a batch; [.., i, j] = ∂f_i/∂x_j."""
        xs, single = rows("x", x, self.nx)
        out = self._native.jac_x(xs, self._u(u, xs.shape[0]))
        return out[0] if single else out

    def jac_u(self, x, u=None) -> np.ndarray:
        """∂f/∂u: (nx, nu) for one state, (n, nx, nu) for a batch."""
        xs, single = rows("x", x, self.nx)
        out = self._native.jac_u(xs, self._u(u, xs.shape[0]))
        return out[0] if single else out

    def jw(self, x, v, u=None) -> np.ndarray:
        """(∂f/∂x)·v, one tangent vector per state: the shape of x."""
        xs, single = rows("x", x, self.nx)
        vs, _ = rows("v", v, self.nx)
        if vs.shape[0] != xs.shape[0]:
            raise InputError(f"v: {vs.shape[0]} rows for {xs.shape[0]} states")
        out = self._native.jw(xs, vs, self._u(u, xs.shape[0]))
        return out[0] if single else out


def _rebuild(name, ir, params, runtime) -> Model:
    return Model(name, ir=ir, params=params, runtime=runtime)


def derive(system, symbols=None, *, params=None) -> Model:
    """Derive a model with twv.modeling (CasADi) and return it, ready to analyse.

    system: a shipped model's name, an `ExplicitModel`, or a `MultibodySystem` built from the
    vehicle parameter symbols `symbols = twv.modeling.vehicle_symbols()` (their defaults come
    from vehicles/paper.toml). The model runs on the interpreter, bit-identical to compiled code.
    """
    import importlib

    modeling = importlib.import_module("twv.modeling")
    return Model(ir=modeling.ir_text(system, symbols), params=params)
