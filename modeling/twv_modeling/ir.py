"""Export a derived model as the model IR (format twv-ir/1, see generated/ir/README.md).

Each function is a CasADi SX Function with inputs (x, u, p), compiled with common-subexpression
elimination, and written as its straight-line instruction list: every instruction defines one new
value (SSA numbering), operations by *name* (CasADi's OP_* numbers are an internal enum).
Constants are written as shortest round-trip decimals. The same model gives the same bytes.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import tempfile
from pathlib import Path

import casadi as ca

from .derived import DerivedModel

FORMAT = "twv-ir/1"
CASADI_VERSION = "3.8.2"
HASH_PLACEHOLDER = "sha256:" + "0" * 64

OP_NAMES = {getattr(ca, n): n[3:].lower() for n in dir(ca) if n.startswith("OP_")}
UNARY = {
    "neg",
    "exp",
    "log",
    "sqrt",
    "sq",
    "twice",
    "sin",
    "cos",
    "tan",
    "asin",
    "acos",
    "atan",
    "fabs",
    "sign",
    "inv",
    "sinh",
    "cosh",
    "tanh",
    "asinh",
    "acosh",
    "atanh",
    "floor",
    "ceil",
    "erf",
    "not",
    "log1p",
    "expm1",
}
BINARY = {
    "add",
    "sub",
    "mul",
    "div",
    "pow",
    "constpow",
    "fmin",
    "fmax",
    "atan2",
    "copysign",
    "fmod",
    "lt",
    "le",
    "eq",
    "ne",
    "and",
    "or",
    "if_else_zero",
    "hypot",
}
MECHANICAL_PARTS = ("M", "Cp", "F", "Q", "energy", "momentum", "steady")


class IRExportError(ValueError):
    pass


def check_casadi_version():
    if ca.__version__ != CASADI_VERSION:
        raise IRExportError(
            f"CasADi {ca.__version__} found, the IR is pinned to {CASADI_VERSION} "
            "(the instruction sequence changes between releases)"
        )


def export_function(name: str, args: list[ca.SX], outputs: list[tuple[str, ca.SX]]) -> dict:
    """Straight-line instruction list of a function of (x, u, p) with the given outputs."""
    fn = ca.Function(name, args, [e for _, e in outputs], {"cse": True, "live_variables": False})
    instructions: list[list] = []
    value_of_work: dict[int, int] = {}
    out_values = [[None] * fn.sparsity_out(i).nnz() for i in range(fn.n_out())]
    for k in range(fn.n_instructions()):
        op = OP_NAMES[fn.instruction_id(k)]
        ins, outs = fn.instruction_input(k), fn.instruction_output(k)
        if op == "output":
            out_values[outs[0]][outs[1]] = value_of_work[ins[0]]
            continue
        vid = len(instructions)
        if op == "input":
            instructions.append([vid, "input", ins[0], ins[1]])
        elif op == "const":
            value = float(fn.instruction_constant(k))
            if not math.isfinite(value):
                raise IRExportError(f"{name}: non-finite constant {value}")
            instructions.append([vid, "const", value])
        elif op in UNARY:
            instructions.append([vid, op, value_of_work[ins[0]]])
        elif op in BINARY:
            instructions.append([vid, op, value_of_work[ins[0]], value_of_work[ins[1]]])
        else:
            raise IRExportError(f"{name}: CasADi operation `{op}` is not supported by twv-ir/1")
        value_of_work[outs[0]] = vid
    result = []
    for i, (oname, _) in enumerate(outputs):
        sp = fn.sparsity_out(i)
        if any(v is None for v in out_values[i]):
            raise IRExportError(f"{name}: output {oname} has unwritten entries")
        result.append(
            {
                "name": oname,
                "rows": sp.size1(),
                "cols": sp.size2(),
                "colind": list(sp.colind()),
                "row": list(sp.row()),
                "values": out_values[i],
            }
        )
    n_ops = sum(1 for ins in instructions if ins[1] not in ("input", "const"))
    return {
        "n_values": len(instructions),
        "n_ops": n_ops,
        "instructions": instructions,
        "outputs": result,
    }


def golden_points(model: DerivedModel) -> list[tuple[list[float], list[float]]]:
    """Fixed evaluation points: the origin (upright at rest) and two generic points."""
    nx, nu = model.x.numel(), model.u.numel()
    points = [([0.0] * nx, [0.0] * nu)]
    for k, scale in ((1, 0.5), (2, 3.0)):
        x = [round(scale * math.sin(0.7 + 1.37 * i + 2.1 * k), 12) for i in range(nx)]
        u = [round(40.0 * math.cos(0.3 + 1.1 * j + k), 12) for j in range(nu)]
        points.append((x, u))
    return points


def build_ir(model: DerivedModel) -> dict:
    check_casadi_version()
    x, u, p = model.x, model.u, model.p
    f = model.expressions["f"]
    jac_x, jac_u = model.jacobian_x(), ca.jacobian(f, u)
    args = [x, u, p]
    functions = {
        "f": export_function("f", args, [("f", f)]),
        "jac_x": export_function("jac_x", args, [("jac_x", jac_x)]),
        "jac_u": export_function("jac_u", args, [("jac_u", jac_u)]),
        "f_jac_x": export_function("f_jac_x", args, [("f", f), ("jac_x", jac_x)]),
    }
    for part in MECHANICAL_PARTS:
        if part in model.expressions:
            functions[part] = export_function(part, args, [(part, model.expressions[part])])

    all_expr = ca.vertcat(*[ca.vec(e) for e in model.expressions.values()])
    defaults = [p.default for p in model.params]
    golden_fn = ca.Function("golden", args, [f, jac_x])
    golden = []
    for xv, uv in golden_points(model):
        fv, jv = golden_fn(xv, uv, defaults)
        golden.append(
            {
                "x": xv,
                "u": uv,
                "f": [float(v) for v in fv.nonzeros()],
                "jac_x": [float(v) for v in jv.nonzeros()],
            }
        )
    return {
        "format": FORMAT,
        "hash": HASH_PLACEHOLDER,
        "model": model.name,
        "kind": model.kind,
        "description": model.description,
        "generator": {"tool": "twv_modeling", "casadi": CASADI_VERSION},
        "states": [_signal(s) for s in model.states],
        "inputs": [_signal(s) for s in model.inputs],
        "params": [
            {
                "name": prm.name,
                "key": prm.toml_key,
                "index": prm.index,
                "unit": prm.unit,
                "kind": prm.kind,
                "default": prm.default,
                "used": bool(ca.depends_on(all_expr, p[i])),
                "description": prm.description,
            }
            for i, prm in enumerate(model.params)
        ],
        "defaults_source": model.params_source,
        **({"mechanics": model.header} if model.header else {}),
        "functions": functions,
        "golden": golden,
    }


def _signal(s) -> dict:
    return {"name": s.name, "unit": s.unit, "description": s.description}


def dumps(ir: dict) -> str:
    """Deterministic text: arrays of scalars on one line (one instruction per line), then the
    content hash (sha256 of the text with the placeholder hash) written in place."""
    text = _dump(ir, 0) + "\n"
    digest = hashlib.sha256(text.encode()).hexdigest()
    return text.replace(HASH_PLACEHOLDER, "sha256:" + digest, 1)


def _dump(obj, level: int) -> str:
    pad, inner = " " * level, " " * (level + 1)
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        items = [f"{inner}{json.dumps(k)}: {_dump(v, level + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list):
        if all(not isinstance(e, dict | list) for e in obj):
            return "[" + ", ".join(_scalar(e) for e in obj) + "]"
        return "[\n" + ",\n".join(inner + _dump(e, level + 1) for e in obj) + "\n" + pad + "]"
    return _scalar(obj)


def _scalar(v) -> str:
    if isinstance(v, float) and not math.isfinite(v):
        raise IRExportError(f"non-finite number {v} cannot be written to the IR")
    return json.dumps(v, allow_nan=False)


def write_atomic(path: Path, text: str):
    """Write via a temporary file in the same folder and rename: never a partial IR file."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=directory)
    try:
        os.chmod(fd, 0o644)
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
