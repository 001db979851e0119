"""CasADi's own C code for a model: the peer the Rust kernels are benchmarked against.

Writes `<model>_casadi.c` (and `.h`) with, for runtime parameters, `<model>_f(x,u,p)`,
`<model>_f_jac_x(x,u,p)` and `<model>_f_jw8(x,u,p,W)` (f and J W for 8 tangent vectors, W an
NX x 8 matrix; another count of tangents names it `f_jw<K>`), and unless told not to the
same with the default parameters folded in (`*_baked`, arguments x, u and W). Parameters are
substituted into f and its Jacobian jointly so that common subexpressions stay shared. The same
for any other f of the model's symbols (the hand-written peer, `hand_peer.py`), under another
name.
"""

from __future__ import annotations

import json
from pathlib import Path

import casadi as ca

from .derived import DerivedModel, operations

TANGENTS = 8


def export_c(
    model: DerivedModel,
    out_dir: Path,
    f: ca.SX | None = None,
    tag: str = "",
    tangents: int = TANGENTS,
    baked: bool = True,
) -> Path:
    """Writes `<model><tag>_casadi.c` for `f` (default: the derivation's), its functions named
    `<model><tag>_f`, ..., and `<model><tag>_ops.json` with their operation counts. `baked`:
    also the functions with the default parameters folded in (the bicycle's peer leaves them
    out: gcc -O3 takes ~20 s per copy of its ∂f/∂x)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    x, u, p = model.x, model.u, model.p
    own = f is None
    f = model.expressions["f"] if own else f
    jac = model.jacobian_x() if own else ca.jacobian(f, x)
    if tangents < 1:
        raise ValueError(f"tangents must be at least 1, not {tangents}")
    W = ca.SX.sym("W", x.numel(), tangents)
    jw = ca.mtimes(jac, W)
    if not own:
        # The derivation's sparsity for the ∂f/∂x output (extra entries are zeros), so both
        # exports are read alike; J·W keeps this f's own, sparser Jacobian.
        jac = ca.project(jac, model.jacobian_x().sparsity())
    defaults = ca.DM([prm.default for prm in model.params])
    opts = {"cse": True}
    m = model.name + tag
    funcs = [
        ca.Function(f"{m}_f", [x, u, p], [f], opts),
        ca.Function(f"{m}_f_jac_x", [x, u, p], [f, jac], opts),
        ca.Function(f"{m}_f_jw{tangents}", [x, u, p, W], [f, jw], opts),
    ]
    if baked:
        folded = ca.substitute([f, jac, jw], [p], [defaults])
        funcs += [
            ca.Function(f"{m}_f_baked", [x, u], [folded[0]], opts),
            ca.Function(f"{m}_f_jac_x_baked", [x, u], [folded[0], folded[1]], opts),
            ca.Function(f"{m}_f_jw{tangents}_baked", [x, u, W], [folded[0], folded[2]], opts),
        ]
    name = f"{m}_casadi"
    cg = ca.CodeGenerator(f"{name}.c", {"with_header": True, "prefix": f"{m}_"})
    for fn in funcs:
        cg.add(fn)
    cg.generate(str(out_dir) + "/")
    counts = {fn.name().removeprefix(f"{m}_"): operations(fn) for fn in funcs[:3]}
    (out_dir / f"{m}_ops.json").write_text(json.dumps(counts, sort_keys=True) + "\n")
    return out_dir / f"{name}.c"
