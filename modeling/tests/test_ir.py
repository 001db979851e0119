"""The IR as a second reader sees it: deterministic bytes, a verifiable hash, a straight-line
program whose evaluation (by the small independent interpreter below) reproduces the golden
values CasADi computed."""

import hashlib
import json
import math

import pytest

from twv_modeling.ir import HASH_PLACEHOLDER, build_ir, dumps
from twv_modeling.models import SHIPPED
from twv_modeling.registry import REPO_ROOT, build

UNARY = {
    "neg": lambda a: -a,
    "sq": lambda a: a * a,
    "twice": lambda a: 2.0 * a,
    "inv": lambda a: 1.0 / a,
    "sin": math.sin,
    "cos": math.cos,
    "sqrt": math.sqrt,
    "exp": math.exp,
    "log": math.log,
    "fabs": abs,
    "tan": math.tan,
}
BINARY = {
    "add": lambda a, b: a + b,
    "sub": lambda a, b: a - b,
    "mul": lambda a, b: a * b,
    "div": lambda a, b: a / b,
    "pow": math.pow,
    "constpow": math.pow,
}


def evaluate(function: dict, args: list[list[float]]) -> list[list[float]]:
    values: list[float] = []
    for ins in function["instructions"]:
        k, op, *rest = ins
        assert k == len(values), "instructions are numbered in order"
        if op == "input":
            values.append(args[rest[0]][rest[1]])
        elif op == "const":
            values.append(float(rest[0]))
        elif op in UNARY:
            assert rest[0] < k
            values.append(UNARY[op](values[rest[0]]))
        else:
            assert rest[0] < k and rest[1] < k
            values.append(BINARY[op](values[rest[0]], values[rest[1]]))
    return [[values[v] for v in out["values"]] for out in function["outputs"]]


@pytest.fixture(scope="module", params=SHIPPED)
def ir_text(request):
    return dumps(build_ir(build(request.param)))


def test_derivation_is_deterministic(ir_text):
    name = json.loads(ir_text)["model"]
    assert dumps(build_ir(build(name))) == ir_text


def test_checked_in_ir_is_current(ir_text):
    name = json.loads(ir_text)["model"]
    assert (REPO_ROOT / "generated" / "ir" / f"{name}.json").read_text() == ir_text


def test_hash_covers_the_content(ir_text):
    ir = json.loads(ir_text)
    blank = ir_text.replace(ir["hash"], HASH_PLACEHOLDER, 1)
    assert ir["hash"] == "sha256:" + hashlib.sha256(blank.encode()).hexdigest()


def test_sparsity_is_consistent(ir_text):
    for fn in json.loads(ir_text)["functions"].values():
        for out in fn["outputs"]:
            assert len(out["colind"]) == out["cols"] + 1
            assert out["colind"][-1] == len(out["row"]) == len(out["values"])
            assert all(0 <= r < out["rows"] for r in out["row"])


def test_second_reader_reproduces_golden_values(ir_text):
    ir = json.loads(ir_text)
    params = [p["default"] for p in ir["params"]]
    for golden in ir["golden"]:
        args = [golden["x"], golden["u"], params]
        (f,) = evaluate(ir["functions"]["f"], args)
        (jac,) = evaluate(ir["functions"]["jac_x"], args)
        f2, jac2 = evaluate(ir["functions"]["f_jac_x"], args)
        for got, want in ((f, golden["f"]), (jac, golden["jac_x"]), (f2, f), (jac2, jac)):
            assert len(got) == len(want)
            for a, b in zip(got, want, strict=True):
                assert abs(a - b) <= 1e-13 * max(1.0, abs(b))


def test_golden_points_include_large_angles():
    ir = build_ir(build("vehicle8"))
    assert max(abs(g["x"][0]) for g in ir["golden"]) > 1.0
