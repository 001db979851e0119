"""Side-by-side benchmark of the bicycle's closed-loop stability map (a benchmark, not a test:
it prints times and ratios; it exits 1 only when the maps disagree).

A 100 speeds × 100 gains map of the benchmark bicycle steered by lean-rate feedback
(T_delta = k_phi_dot · lean rate, speeds 0.5–10 m/s, k_phi_dot −20…60 N m s/rad), the metric
of the vehicle's maps (the closed loop's largest eigenvalue real part), computed
  1. by twv from Python (`twv.steer_map`) and by the CLI (`twv steer-map`, process start and
     model load included),
  2. by python-control as a researcher would write it: the benchmark matrices
     (Meijaard et al. 2007, Appendix A, from the same parameter file), `control.ss`,
     `control.feedback(sys, K, sign=+1)` and `control.poles` per cell,
  3. by NumPy alone: A + b K for every cell stacked, one batched `np.linalg.eigvals`.
The maps must agree cell by cell to 1e-9 (relative to max(1, |value|)).

Build the extension optimised first (the test command does):
    cargo build --release -p twv-cli
    .venv/bin/python python/benches/steer_map_peers.py [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import control
import numpy as np
from twv_modeling.whipple_benchmark import benchmark_matrices, read_parameters

import twv

ROOT = Path(__file__).resolve().parents[2]
SPEEDS = (0.5, 10.0, 100)
VALUES = (-20.0, 60.0, 100)
TOLERANCE = 1e-9


def cpu() -> str:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor()
    name = next(
        (ln.split(":", 1)[1].strip() for ln in text.splitlines() if ln.startswith("model name")),
        "?",
    )
    isa = "AVX-512" if " avx512f" in text else "AVX2" if " avx2" in text else "SSE2"
    return f"{name}, {isa}, {os.cpu_count()} cores"


def best(fn, repeat: int):
    """The best wall time over `repeat` calls [s], and the last call's value."""
    times, value = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        value = fn()
        times.append(time.perf_counter() - t)
    return min(times), value


def axis(a) -> np.ndarray:
    return np.linspace(a[0], a[1], a[2])


def plant(v: float):
    b = benchmark_matrices(read_parameters())
    a = b.state_matrix(v)
    col = np.zeros(4)
    col[2:] = np.linalg.inv(b.M)[:, 1]
    return a, col


def python_control_map() -> np.ndarray:
    speeds, values = axis(SPEEDS), axis(VALUES)
    out = np.empty((len(values), len(speeds)))
    for i, v in enumerate(speeds):
        a, col = plant(v)
        sys_ = control.ss(a, col[:, None], np.eye(4), np.zeros((4, 1)))
        for j, x in enumerate(values):
            k = np.array([[0.0, 0.0, x, 0.0]])
            out[j, i] = control.poles(control.feedback(sys_, k, sign=+1)).real.max()
    return out


def numpy_map() -> np.ndarray:
    speeds, values = axis(SPEEDS), axis(VALUES)
    mats = np.empty((len(values), len(speeds), 4, 4))
    for i, v in enumerate(speeds):
        a, col = plant(v)
        mats[:, i] = a
        mats[:, i, :, 2] += np.outer(values, col)
    return np.linalg.eigvals(mats).real.max(axis=-1)


def twv_map() -> np.ndarray:
    text = lambda a: f"{a[0]}:{a[1]}:{a[2]}"  # noqa: E731
    r = twv.steer_map(
        twv.Model("whipple"), speed=text(SPEEDS), gain="k_phi_dot", values=text(VALUES)
    )
    return r.abscissa


def cli_map() -> np.ndarray:
    exe = ROOT / "target" / "release" / "twv"
    args = [
        str(exe),
        "steer-map",
        "--model",
        "whipple",
        "--gain",
        "k_phi_dot",
        "--speed",
        f"{SPEEDS[0]}:{SPEEDS[1]}:{SPEEDS[2]}",
        "--values",
        f"{VALUES[0]}:{VALUES[1]}:{VALUES[2]}",
        "--json",
    ]
    out = subprocess.run(args, capture_output=True, text=True, check=True)
    raw = json.loads(out.stdout)
    flat = [np.nan if a is None else a for a in raw["abscissa"]]
    return np.array(flat).reshape(VALUES[2], SPEEDS[2])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="calls per path; the best counts")
    args = ap.parse_args()
    print(f"# the bicycle's 100 × 100 closed-loop stability map, on {cpu()}")
    python = sys.version.split()[0]
    print(f"# python-control {control.__version__}, NumPy {np.__version__}, Python {python}")
    paths = [
        ("twv from Python (twv.steer_map)", twv_map),
        ("twv CLI (twv steer-map, process start included)", cli_map),
        ("python-control (ss, feedback, poles per cell)", python_control_map),
        ("NumPy (A + b K stacked, one batched eigvals)", numpy_map),
    ]
    results = []
    for name, fn in paths:
        t, m = best(fn, args.repeat if "python-control" not in name else max(1, args.repeat // 2))
        results.append((name, t, m))
    reference = results[0][1]
    print(
        "# twv's time includes loading the model (the bicycle derived from bodies and contacts),\n"
        "# its 100 linearisations at the speeds and its self-stable band; the peers start from\n"
        "# the closed-form benchmark matrices (Appendix A) and find no band."
    )
    print(f"{'path':<60} {'time':>10} {'÷ twv (Python)':>15}")
    for name, t, _ in results:
        print(f"{name:<60} {t * 1e3:>8.1f} ms {t / reference:>14.1f}×")
    ours = results[0][2]
    worst = 0.0
    for name, _, m in results[1:]:
        err = np.nanmax(np.abs(m - ours) / np.maximum(1.0, np.abs(ours)))
        worst = max(worst, err)
        print(f"largest difference from twv's map, {name.split(' (')[0]}: {err:.1e}")
    if not worst <= TOLERANCE:
        print(f"FAILED: the maps differ by {worst:.1e} > {TOLERANCE:.0e}")
        return 1
    print(f"every path's map equals twv's within {TOLERANCE:.0e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
