"""Command line: `python -m twv_modeling derive|check|summary|export-c|bicycles`.

Errors are one line on stderr and a non-zero exit; IR files are written atomically.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from .explicit import ExplicitModelError
from .ir import IRExportError, build_ir, dumps, write_atomic
from .models import SHIPPED
from .multibody import ModelError
from .params import ParamFileError
from .registry import REPO_ROOT, UnknownModelError, build, build_file

IR_DIR = REPO_ROOT / "generated" / "ir"
USER_ERRORS = (ExplicitModelError, IRExportError, ModelError, ParamFileError, UnknownModelError)


def derive_to(name: str | None, file: Path | None, out: Path) -> dict:
    model = build_file(file) if file is not None else build(name)
    ir = build_ir(model)
    try:
        write_atomic(out, dumps(ir))
    except OSError as err:
        raise IRExportError(f"{out}: cannot write: {err.strerror}") from err
    return ir


def cmd_derive(args) -> int:
    if args.all:
        out_dir = Path(args.out_dir)
        start = time.perf_counter()
        for name in SHIPPED:
            ir = derive_to(name, None, out_dir / f"{name}.json")
            counts = ", ".join(f"{k} {v['n_ops']}" for k, v in ir["functions"].items())
            print(f"{name}: {counts}")
        print(f"derived {len(SHIPPED)} models in {time.perf_counter() - start:.2f} s")
        return 0
    if args.out is None:
        raise IRExportError("derive --model/--file needs --out PATH")
    derive_to(args.model, Path(args.file) if args.file else None, Path(args.out))
    return 0


def cmd_check(args) -> int:
    ir_dir = Path(args.ir_dir)
    stale = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in SHIPPED:
            fresh = Path(tmp) / f"{name}.json"
            derive_to(name, None, fresh)
            current = ir_dir / f"{name}.json"
            if not current.is_file() or current.read_bytes() != fresh.read_bytes():
                stale.append(str(current))
    extra = sorted(str(p) for p in ir_dir.glob("*.json") if p.stem not in SHIPPED)
    if stale or extra:
        for path in stale:
            print(f"stale IR: {path} (run `python -m twv_modeling derive --all`)", file=sys.stderr)
        for path in extra:
            print(f"unexpected IR: {path} (not a shipped model)", file=sys.stderr)
        return 1
    print(f"IR up to date: {len(SHIPPED)} models in {ir_dir}")
    return 0


def cmd_summary(args) -> int:
    names = SHIPPED if args.model is None else (args.model,)
    for name in names:
        model = build(name)
        print(f"== {model.name} ({model.kind}): {model.description}")
        print("   states: " + ", ".join(f"{s.name} [{s.unit}]" for s in model.states))
        print("   inputs: " + (", ".join(f"{s.name} [{s.unit}]" for s in model.inputs) or "none"))
        print(
            f"   params ({model.params_source}): "
            + ", ".join(f"{p.name}={p.default:g}" for p in model.params)
        )
        for part in ("M", "Cp", "F", "Q"):
            if part in model.expressions:
                print(f"   {part} = {model.expressions[part]}")
    return 0


def cmd_export_c(args) -> int:
    from .cgen import export_c

    model = build(args.model)
    out = Path(args.out_dir)
    print(export_c(model, out, tangents=args.tangents, baked=not args.runtime_only))
    if args.hand:
        from .hand_peer import vehicle8_by_hand

        if args.model != "vehicle8":
            print("export-c --hand: the hand-written peer exists for vehicle8 only")
            return 2
        print(export_c(model, Path(args.out_dir), vehicle8_by_hand(model), tag="_hand"))
    return 0


def cmd_bicycles(args) -> int:
    from . import bicycles

    out = Path(args.out_dir)
    if args.check:
        stale = bicycles.stale(out)
        for path in stale:
            print(
                f"stale bicycle file: {path} (run `python -m twv_modeling bicycles`)",
                file=sys.stderr,
            )
        if stale:
            return 1
        print(f"bicycle files up to date: {len(bicycles.available())} in {out}")
        return 0
    for path in bicycles.write_all(out):
        print(f"wrote {path}")
    return 0


def _positive(text: str) -> int:
    """An argument that must be a whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of at least 1")
    return value


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m twv_modeling", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)
    d = sub.add_parser("derive", help="derive models and write their IR")
    which = d.add_mutually_exclusive_group(required=True)
    which.add_argument("--all", action="store_true", help="every shipped model into --out-dir")
    which.add_argument(
        "--model", choices=SHIPPED, metavar="NAME", help=f"one shipped model ({', '.join(SHIPPED)})"
    )
    which.add_argument("--file", help="a user's explicit-ODE model file (defines model())")
    d.add_argument("--out", help="output IR path (with --model or --file)")
    d.add_argument("--out-dir", default=str(IR_DIR), help="output folder for --all")
    d.set_defaults(run=cmd_derive)
    c = sub.add_parser("check", help="fail, naming the files, if checked-in IR is stale")
    c.add_argument("--ir-dir", default=str(IR_DIR))
    c.set_defaults(run=cmd_check)
    s = sub.add_parser("summary", help="print the derived equations of the shipped models")
    s.add_argument("--model", choices=SHIPPED, metavar="NAME")
    s.set_defaults(run=cmd_summary)
    e = sub.add_parser("export-c", help="write CasADi's own C code of a model (benchmark peer)")
    e.add_argument("--model", choices=SHIPPED, metavar="NAME", required=True)
    e.add_argument("--out-dir", required=True)
    e.add_argument(
        "--hand", action="store_true", help="also the hand-written peer (vehicle8: `_hand`)"
    )
    e.add_argument(
        "--tangents", type=_positive, default=8, help="tangent vectors of f_jw<K> (default 8)"
    )
    e.add_argument(
        "--runtime-only", action="store_true", help="no *_baked functions (defaults folded in)"
    )
    e.set_defaults(run=cmd_export_c)
    b = sub.add_parser(
        "bicycles",
        help="write the measured bicycles of bicycleparameters' data set as parameter files",
    )
    b.add_argument("--out-dir", default=str(REPO_ROOT / "vehicles" / "bicycles"))
    b.add_argument("--check", action="store_true", help="fail, naming them, if the files differ")
    b.set_defaults(run=cmd_bicycles)
    return ap


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    try:
        return args.run(args)
    except USER_ERRORS as err:
        print(f"twv_modeling: error: {err}", file=sys.stderr)
        return 2
