"""Side-by-side benchmark of the twv Python package (a benchmark, not a test: it prints times
and ratios and asserts nothing).

In one run, on vehicle8 with the paper parameters:
  1. per-call overhead of f on one state: twv vs a CasADi Function call;
  2. f + ∂f/∂x on 10^5 states: twv's batch vs CasADi's Function.map (serial and thread-
     parallel) and vs NumPy-vectorised code (the IR's instructions as array operations);
  3. the study-preset spectrum (8 exponents, RK4 h = 1e-3, T = 0.1 s, K = 100) from Python vs
     the NumPy + CasADi implementation of the same algorithm and vs jitcode (if installed);
  4. a 100×100 max-Lyapunov map from Python vs the same map from the CLI;
  5. a few jobs from Python vs the same jobs' compute time in the CLI (its process start
     measured and taken off).

Build the extension optimised first:
    VIRTUAL_ENV=$PWD/.venv .venv/bin/maturin develop --release -m python/Cargo.toml
    cargo build --release -p twv-cli
    .venv/bin/python python/benches/python_peers.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

import twv

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "analysis" / "benches"))


def best(fn, repeat: int = 7, number: int = 1) -> float:
    """The best wall time of `number` calls, over `repeat` tries [s per call]."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t) / number)
    return min(times)


def cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                name = line.split(":", 1)[1].strip()
                flags = Path("/proc/cpuinfo").read_text()
                isa = "AVX-512" if " avx512f" in flags else "AVX2" if " avx2" in flags else "SSE2"
                return f"{name}, {isa}, {os.cpu_count()} cores"
    except OSError:
        pass
    return platform.processor()


def casadi_functions():
    from twv_modeling.registry import build

    m = build("vehicle8")
    p = np.array([prm.default for prm in m.params])
    f = m.expressions["f"]
    fj = ca.Function("fj", [m.x, m.u, m.p], [f, ca.jacobian(f, m.x)])
    fo = ca.Function("f", [m.x, m.u, m.p], [f])
    return fo, fj, p


def numpy_ir(ir: dict, params: np.ndarray):
    """f and jac_x of the IR's `f_jac_x` as NumPy array operations over a batch (the
    straight-line program run once per instruction on whole arrays; columns are states)."""
    unary = {
        "neg": np.negative,
        "sin": np.sin,
        "cos": np.cos,
        "tan": np.tan,
        "sqrt": np.sqrt,
        "sq": np.square,
        "exp": np.exp,
        "log": np.log,
        "inv": np.reciprocal,
        "fabs": np.abs,
        "twice": lambda a: 2.0 * a,
        "log1p": np.log1p,
        "expm1": np.expm1,
    }
    binary = {
        "add": np.add,
        "sub": np.subtract,
        "mul": np.multiply,
        "div": np.divide,
        "pow": np.power,
        "constpow": np.power,
        "atan2": np.arctan2,
    }
    fn = ir["functions"]["f_jac_x"]

    def run(x, u):
        args = (x, u, params[:, None])
        w = [None] * fn["n_values"]
        for k, op, *a in fn["instructions"]:
            if op == "input":
                w[k] = args[a[0]][a[1]]
            elif op == "const":
                w[k] = a[0]
            elif len(a) == 1:
                w[k] = unary[op](w[a[0]])
            else:
                w[k] = binary[op](w[a[0]], w[a[1]])
        return [[w[v] for v in out["values"]] for out in fn["outputs"]]

    return run


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="smaller sizes, fewer repeats")
    args = ap.parse_args()
    n_batch = 20_000 if args.quick else 100_000
    rows = []
    print(f"CPU: {cpu()}; Python {platform.python_version()}, casadi {ca.__version__}")
    model = twv.Model("vehicle8")
    fo, fj, p = casadi_functions()
    x1 = np.array([0.1, 0.2, -0.3, 0.4, 0.5, -0.6, 0.7, -0.8])
    u1 = np.array([10.0, -2.0])
    assert np.allclose(model.f(x1, u1), np.array(fo(x1, u1, p)).ravel(), rtol=1e-13, atol=1e-14)

    # 1. One state.
    t_twv = best(lambda: model.f(x1, u1), number=20_000)
    t_ca = best(lambda: fo(x1, u1, p), number=20_000)
    rows.append(("f, one state (per call)", t_twv, "CasADi Function call", t_ca))

    # 2. Batch f + jac_x.
    rng = np.random.default_rng(1)
    X = rng.uniform(-1, 1, (n_batch, 8))
    U = rng.uniform(-100, 100, (n_batch, 2))
    t_twv = best(lambda: (model.f(X, U), model.jac_x(X, U)), repeat=5)
    Xt, Ut = np.ascontiguousarray(X.T), np.ascontiguousarray(U.T)
    Pt = np.repeat(p[:, None], n_batch, axis=1)
    serial = fj.map(n_batch, "serial")
    thread = fj.map(n_batch, "thread", os.cpu_count() or 2)
    t_serial = best(lambda: serial(Xt, Ut, Pt), repeat=3)
    t_thread = best(lambda: thread(Xt, Ut, Pt), repeat=3)
    fx, jx = thread(Xt, Ut, Pt)
    assert np.allclose(np.array(fx).T, model.f(X, U), rtol=1e-12, atol=1e-12)
    label = f"f + jac_x, {n_batch:,} states"
    rows.append((label, t_twv, "CasADi map serial", t_serial))
    rows.append((label, t_twv, "CasADi map thread", t_thread))
    ir = json.loads((ROOT / "generated" / "ir" / "vehicle8.json").read_text())
    run = numpy_ir(ir, p)
    f_np = np.array(run(Xt, Ut)[0])
    assert np.allclose(f_np.T, model.f(X, U), rtol=1e-12, atol=1e-12)
    t_np = best(lambda: run(Xt, Ut), repeat=3)
    rows.append((label, t_twv, "NumPy vectorised (IR ops)", t_np))

    # 3. The study-preset spectrum.
    x0 = [0.1, 0, 0, 0, 0, 0, 0, 0]
    spec = lambda: twv.lyapunov(model, x0, preset="paper", running=False)  # noqa: E731
    t_twv = best(spec, repeat=20)
    from lyapunov_peers import rk4_numpy_casadi

    t = time.perf_counter()
    ref = rk4_numpy_casadi(np.array(x0), 1e-3, 0.1, 10 if args.quick else 100)
    t_np = (time.perf_counter() - t) * (10 if args.quick else 1)
    rows.append(("study-preset spectrum", t_twv, "NumPy + CasADi (same algorithm)", t_np))
    del ref
    try:
        from lyapunov_peers import jitcode_spectrum

        # Its integration time, without its C compile (a one-off per model).
        _, elapsed, _ = jitcode_spectrum(np.array(x0), 0.1, 100)
        rows.append(("study-preset spectrum", t_twv, "jitcode (dopri5 at 1e-10)", elapsed))
    except ImportError:
        print("(jitcode not installed: pip install -r analysis/benches/requirements.txt)")

    # 4. The 100×100 map from Python and from the CLI, alternately.
    n = 30 if args.quick else 100
    binary = ROOT / "target" / "release" / "twv"
    py_times, cli_times = [], []
    for _ in range(2 if args.quick else 4):
        t = time.perf_counter()
        twv.sweep(model, kp=(0, 8000, n), kd=(0, 4000, n))
        py_times.append(time.perf_counter() - t)
        with tempfile.TemporaryDirectory() as d:
            t = time.perf_counter()
            subprocess.run(
                [
                    str(binary),
                    "sweep",
                    "--kp",
                    f"0:8000:{n}",
                    "--kd",
                    f"0:4000:{n}",
                    "--metric",
                    "max-lyapunov",
                    "--out",
                    d,
                    "--quiet",
                ],
                check=True,
            )
            cli_times.append(time.perf_counter() - t)
    rows.append((f"{n}×{n} max-Lyapunov map", min(py_times), "twv CLI", min(cli_times)))

    print("\n| task | twv from Python | peer | peer time | peer / twv |\n|---|---:|---|---:|---:|")
    for task, ours, peer, theirs in rows:
        print(f"| {task} | {fmt(ours)} | {peer} | {fmt(theirs)} | {theirs / ours:.2f} |")
    python_against_cli(binary, args.quick)


# The same jobs from Python and from the CLI: (job, model, options), the options as the CLI
# takes them (the Python keyword arguments are the same names with the same values).
SAME_JOBS = [
    ("lyapunov", "vehicle8", {"x0": "0.1,0,0,0,0,0,0,0", "preset": "paper"}),
    ("lyapunov", "whipple", {"speed": "3", "steer_gains": "k_phi_dot=15", "h": "0.01"}),
    ("ride", "whipple", {"speed": "3", "perturb": "w_phi=0.5", "steer_gains": "k_phi_dot=15"}),
    ("steer_map", "whipple", {"speed": "0.5:10:100", "values": "-20:60:100"}),
    ("steer", "whipple", {}),
]


def python_against_cli(binary: Path, quick: bool) -> None:
    """Each job of SAME_JOBS from Python (model loading included) and from the CLI (`--json`,
    the result on stdout), alternately, best of several. The CLI's time includes starting a
    process, measured alone as `twv --version`; the job's compute time in the CLI is the
    difference, and the goal is Python ≤ 1.1 × that."""
    repeat = 3 if quick else 7

    def cli(argv):
        subprocess.run([str(binary), *argv], check=True, stdout=subprocess.DEVNULL)

    start = best(lambda: cli(["--version"]), repeat=repeat * 3)
    print(
        f"\nThe same jobs from Python and the CLI (the CLI's process start, `twv --version`: "
        f"{fmt(start)})\n\n| job | model | Python | CLI | CLI − start | Python / (CLI − start) |"
        "\n|---|---|---:|---:|---:|---:|"
    )
    for job, model, options in SAME_JOBS:
        flags = [f"--{k.replace('_', '-')}={v}" for k, v in options.items()]
        argv = [job.replace("_", "-"), "--model", model, *flags, "--json", "--quiet"]
        run = getattr(twv, job)
        t_py, t_cli = [], []
        for _ in range(repeat):
            t = time.perf_counter()
            run(twv.Model(model), **options)
            t_py.append(time.perf_counter() - t)
            t = time.perf_counter()
            cli(argv)
            t_cli.append(time.perf_counter() - t)
        ours, theirs = min(t_py), min(t_cli)
        compute = theirs - start
        print(
            f"| {job} | {model} | {fmt(ours)} | {fmt(theirs)} | {fmt(compute)} | "
            f"{ours / compute:.2f} |"
        )


def fmt(seconds: float) -> str:
    if seconds < 1e-3:
        return f"{seconds * 1e6:.2f} µs"
    if seconds < 1:
        return f"{seconds * 1e3:.2f} ms"
    return f"{seconds:.2f} s"


if __name__ == "__main__":
    main()
