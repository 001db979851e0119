"""Side-by-side Lyapunov spectrum benchmark on the study's preset (issue 5).

Runs, in one invocation, the same problem — vehicle8 with the paper parameters, 8 exponents,
RK4 with h = 1e-3, re-orthonormalisation every T = 0.1 s, K = 100 intervals — with
  (1) twv (`twv lyap --timing`),
  (2) jitcode (its Lyapunov integrator on the same equations, converted from the IR to symengine;
      it has no fixed-step RK4, so it runs its adaptive dopri5 at tight tolerance, and starts
      from random tangent vectors, so its first interval is discarded),
  (3) a NumPy implementation of the same algorithm evaluating CasADi functions,
and prints the spectra, their sums (independent of the tangent basis: the time average of tr J),
and the time ratios.  Usage: .venv/bin/python analysis/benches/lyapunov_peers.py [--x0 ...]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
IR = ROOT / "generated" / "ir" / "vehicle8.json"


def rk4_numpy_casadi(x0, h, t_sample, iterations):
    """The Benettin/QR algorithm in NumPy, f and J from CasADi (the peer written in Python)."""
    from twv_modeling.registry import build

    m = build("vehicle8")
    p = [prm.default for prm in m.params]
    f = m.expressions["f"]
    fj = ca.Function("fj", [m.x, m.u, m.p], [f, ca.jacobian(f, m.x)])
    u = np.zeros(2)
    n = len(x0)

    def rhs(x, W):
        fx, J = fj(x, u, p)
        return np.array(fx).ravel(), np.array(J) @ W

    x, W = np.array(x0, float), np.eye(n)
    sums = np.zeros(n)
    steps = round(t_sample / h)
    for _ in range(iterations):
        for _ in range(steps):
            k1x, k1w = rhs(x, W)
            k2x, k2w = rhs(x + h / 2 * k1x, W + h / 2 * k1w)
            k3x, k3w = rhs(x + h / 2 * k2x, W + h / 2 * k2w)
            k4x, k4w = rhs(x + h * k3x, W + h * k3w)
            x = x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            W = W + h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w)
        Q, R = np.linalg.qr(W)
        signs = np.sign(np.diag(R))
        W = Q * signs
        sums += np.log(np.abs(np.diag(R)))
    return np.sort(sums / (iterations * t_sample))[::-1]


def ir_to_symengine(ir, y, params):
    """f of the IR as symengine expressions of jitcode's y(i), parameters at their defaults."""
    import symengine as se

    unary = {
        "neg": lambda a: -a,
        "sq": lambda a: a * a,
        "twice": lambda a: 2 * a,
        "inv": lambda a: 1 / a,
        "sin": se.sin,
        "cos": se.cos,
        "sqrt": se.sqrt,
        "exp": se.exp,
        "log": se.log,
        "tan": se.tan,
    }
    binary = {
        "add": lambda a, b: a + b,
        "sub": lambda a, b: a - b,
        "mul": lambda a, b: a * b,
        "div": lambda a, b: a / b,
        "pow": lambda a, b: a**b,
        "constpow": lambda a, b: a**b,
    }
    fn = ir["functions"]["f"]
    values = []
    for k, op, *rest in fn["instructions"]:
        if op == "input":
            arg, i = rest
            values.append(
                y(i) if arg == 0 else se.Float(0.0 if arg == 1 else params[i])
            )
        elif op == "const":
            values.append(se.Float(rest[0]))
        elif op in unary:
            values.append(unary[op](values[rest[0]]))
        else:
            values.append(binary[op](values[rest[0]], values[rest[1]]))
    out = fn["outputs"][0]
    return [values[v] for v in out["values"]]


def jitcode_spectrum(x0, t_sample, iterations):
    from jitcode import jitcode_lyap, y

    ir = json.loads(IR.read_text())
    params = [p["default"] for p in ir["params"]]
    f = ir_to_symengine(ir, y, params)
    ode = jitcode_lyap(f, n_lyap=len(x0), simplify=False, verbose=False)
    start = time.perf_counter()
    ode.compile_C()
    compile_time = time.perf_counter() - start
    ode.set_integrator("dopri5", atol=1e-10, rtol=1e-10)
    ode.set_initial_value(np.array(x0, float), 0.0)
    start = time.perf_counter()
    local = []
    for k in range(1, iterations + 2):
        _, lyaps, _ = ode.integrate(k * t_sample)
        local.append(lyaps)
    elapsed = time.perf_counter() - start
    spectrum = np.mean(
        local[1:], axis=0
    )  # the first interval starts from random vectors
    return np.sort(spectrum)[::-1], elapsed, compile_time


def twv_run(x0, *extra):
    exe = ROOT / "target" / "release" / "twv"
    cmd = [
        str(exe),
        "lyap",
        "--model",
        "vehicle8",
        "--preset",
        "paper",
        "--integrator",
        "rk4",
        "--h",
        "1e-3",
        "--x0",
        ",".join(map(str, x0)),
        "--json",
        *extra,
    ]
    return json.loads(
        subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    )


def twv_spectrum(x0, repeat):
    out = twv_run(x0, "--timing", str(repeat))
    return np.array(out["exponents"]), out["timing"]["seconds_per_run"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--x0", default="0.1,0,0,0,0,0,0,0", help="initial state (vehicle8 order)"
    )
    ap.add_argument(
        "--repeat", type=int, default=200, help="twv runs averaged for its timing"
    )
    args = ap.parse_args()
    x0 = [float(v) for v in args.x0.split(",")]
    subprocess.run(
        ["cargo", "build", "--quiet", "--release", "--bin", "twv"], cwd=ROOT, check=True
    )
    t_sample, iterations, h = 0.1, 100, 1e-3

    twv, t_twv = twv_spectrum(x0, args.repeat)
    start = time.perf_counter()
    numpy_spec = rk4_numpy_casadi(x0, h, t_sample, iterations)
    t_numpy = time.perf_counter() - start
    jit, t_jit, t_jit_compile = jitcode_spectrum(x0, t_sample, iterations)

    rows = [
        ("twv (Rust, RK4, identity basis)", twv, t_twv),
        ("jitcode (dopri5 1e-10, random basis, 1st interval dropped)", jit, t_jit),
        ("NumPy + CasADi (RK4, identity basis)", numpy_spec, t_numpy),
    ]
    print(f"vehicle8, x0 = {x0}, T = {t_sample} s, K = {iterations}, h = {h}")
    for name, spec, secs in rows:
        print(
            f"{name}\n  exponents: {np.array2string(spec, precision=4)}\n"
            f"  sum: {spec.sum():+.6e}   time: {secs * 1e3:.3f} ms   "
            f"ratio to twv: {secs / t_twv:.0f}x"
        )
    print(f"(jitcode compile time, not counted: {t_jit_compile:.1f} s)")
    same_window = twv_run(x0, "--transient", "0.1")
    print(
        f"sum over jitcode's window [0.1, 10.1] s: twv {same_window['sum']:+.6e} "
        f"(<tr J> {same_window['mean_trace']:+.6e}), jitcode {jit.sum():+.6e}"
    )
    print(
        "individual finite-time exponents depend on the basis; they converge as T*K grows:"
    )
    for iterations in (100, 1000, 10000):
        for basis in ([], ["--seed", "1"]):
            out = twv_run(x0, "--iterations", str(iterations), *basis)
            name = "random (seed 1)" if basis else "identity"
            print(
                f"  twv T*K = {iterations * t_sample:>6.0f} s, {name:<15} "
                f"{np.array2string(np.array(out['exponents']), precision=4)}"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
