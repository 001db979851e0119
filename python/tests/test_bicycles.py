"""The measured bicycles (vehicles/bicycles/, converted from the `bicycleparameters` data set by
`python -m twv_modeling bicycles`): the files are what the conversion writes today; each
file's canonical matrices M, C1, K0, K2 (the closed-form Appendix A of Meijaard et al. 2007 on
the file's values) equal the package's own `Bicycle.canonical()`; and twv's weave and capsize
speeds (its derived nonlinear model, linearised) equal those of the package's own eigenvalue
routine `Bicycle.eig`, found on its eigenvalues by bisection."""

from __future__ import annotations

import contextlib
import io
import warnings

import bicycleparameters
import numpy as np
import pytest
from conftest import REPO
from scipy.optimize import brentq
from twv_modeling import bicycles
from twv_modeling.whipple_benchmark import benchmark_matrices, read_parameters

import twv

FOLDER = REPO / "vehicles" / "bicycles"
NAMES = bicycles.available()


def package_bicycle(name: str):
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return bicycleparameters.Bicycle(name, pathToData=str(bicycles.data_dir()))


def test_the_files_are_what_the_conversion_writes():
    assert len(NAMES) >= 9 and "Browser" in NAMES and "Benchmark" in NAMES
    assert bicycles.stale(FOLDER) == []


@pytest.mark.parametrize("name", NAMES)
def test_each_file_has_the_packages_canonical_matrices(name):
    theirs = package_bicycle(name).canonical(nominal=True)
    ours = benchmark_matrices(read_parameters(FOLDER / f"{name.lower()}.toml"))
    for label, a, b in zip(
        ("M", "C1", "K0", "K2"), (ours.M, ours.C1, ours.K0, ours.K2), theirs, strict=True
    ):
        assert np.allclose(a, np.asarray(b, dtype=float), rtol=1e-12, atol=1e-12), (name, label)


def package_abscissa(bike, v: float) -> tuple[float, bool]:
    """The largest real part of the package's eigenvalues at v, and whether that eigenvalue is
    part of a complex pair."""
    ev = np.asarray(bike.eig(np.array([v]))[0]).ravel()
    top = ev[np.argmax(ev.real)]
    return float(top.real), bool(abs(top.imag) > 1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_weave_and_capsize_speeds_are_the_packages(name):
    bike = package_bicycle(name)
    steady = twv.steady(
        twv.Model("whipple", params=FOLDER / f"{name.lower()}.toml"), speed=(0, 10, 0.01)
    )
    ranges = steady.raw["ranges"]
    # The package's sign changes of the largest real part on the same grid, refined by bisection.
    grid = np.arange(0, 10.0 + 1e-9, 0.01)
    signs = [package_abscissa(bike, v)[0] < 0 for v in grid]
    crossings = [
        brentq(lambda v: package_abscissa(bike, v)[0], grid[i], grid[i + 1], xtol=1e-12)
        for i in range(len(grid) - 1)
        if signs[i] != signs[i + 1]
    ]
    ours = [b for r in ranges for b in (r["lo"], r["hi"]) if b not in (0.0, 10.0)]
    assert len(ours) == len(crossings), (name, ours, crossings)
    for a, b in zip(ours, crossings, strict=True):
        assert abs(a - b) < 1e-6, (name, a, b)
    if steady.weave_speed is not None:
        assert abs(steady.weave_speed - crossings[0]) < 1e-6
        assert package_abscissa(bike, steady.weave_speed - 1e-3)[1], "a complex pair crosses"


def test_each_draw_of_the_monte_carlo_is_the_closed_form_bicycle_of_its_values():
    """`twv.uncertainty` on Pista: every draw's weave and capsize speeds (twv's derived model,
    linearised) equal those of the closed-form Appendix A matrices of the values the draw
    records (a second derivation), and the values vary by the file's standard deviations."""
    model = twv.Model("whipple", params=FOLDER / "pista.toml")
    r = twv.uncertainty(model, samples=6, speeds="2:8", gains="k_phi=20,k_phi_dot=10", seed=3)
    assert r.draws.shape == (6, len(r.names)) and r.ok
    assert r.weave_speeds.shape == (6,) and bool(np.all(r.stable))
    nominal = read_parameters(FOLDER / "pista.toml")
    varied = {v["name"] for v in r.varied}
    for j, name in enumerate(r.names):
        if name not in varied:
            assert np.all(r.draws[:, j] == nominal[name]), name
    for k in range(6):
        values = dict(zip(r.names, r.draws[k], strict=True))
        band = benchmark_matrices(values).stable_speed_range(lo=2.0, hi=8.0, step=0.05)
        assert band is not None
        assert abs(r.weave_speeds[k] - band[0]) < 1e-6, (k, r.weave_speeds[k], band)
        assert abs(r.capsize_speeds[k] - band[1]) < 1e-6, (k, r.capsize_speeds[k], band)
    frame = r.to_pandas()
    assert list(frame["index"]) == list(range(6)) and "lambda" in frame.columns


def test_the_steered_linearisation_is_python_controls_feedback_on_the_closed_form_bicycle():
    """`twv.linearize(speed=, steer_gains=)` on Browser at 3 m/s: the steer loop's poles are
    those of python-control's `feedback` of the closed-form Appendix A plant with the same
    gains (a second derivation, a second library), and its classical phase margin at the steer
    torque is python-control's `stability_margins` of L(s) = -K (sI - A)^-1 b."""
    control = pytest.importorskip("control")
    model = twv.Model("whipple", params=FOLDER / "browser.toml")
    gains = {"k_phi": 5.0, "k_delta": 0.0, "k_phi_dot": 15.0, "k_delta_dot": 0.0}
    lin = twv.linearize(model, speed=3.0, steer_gains=gains)
    st = lin.steer
    assert lin.margins is None and lin.loop_poles.size == 0  # no pitch
    bench = benchmark_matrices(read_parameters(FOLDER / "browser.toml"))
    a = bench.state_matrix(3.0)
    b = np.zeros((4, 1))
    b[2:, 0] = np.linalg.inv(bench.M)[:, 1]
    k = np.array([[gains["k_phi"], gains["k_delta"], gains["k_phi_dot"], gains["k_delta_dot"]]])
    plant = control.ss(a, b, np.eye(4), np.zeros((4, 1)))
    closed = control.feedback(plant, k, sign=1)
    theirs = np.sort_complex(control.poles(closed))
    ours = np.sort_complex(st["poles"])
    assert np.allclose(ours, theirs, rtol=1e-8, atol=1e-8), (ours, theirs)
    assert st["stable"] == bool(np.all(theirs.real < 0))
    loop = -control.ss(a, b, k, np.zeros((1, 1)))
    _, pm, sm, _, wgc, _ = control.stability_margins(loop)
    m = st["margins"]
    assert m is not None
    assert abs(m["phase_margin"]["deg"] - pm) < 1e-3, (m, pm)
    assert abs(m["phase_margin"]["frequency"] - wgc) < 1e-3 * wgc
    # python-control's stability margin is the Nyquist curve's distance to -1: 1 / peak |S|.
    assert abs(m["peak_sensitivity"] - 1 / sm) < 1e-3 * m["peak_sensitivity"], (m, sm)


def test_the_rate_filtered_steer_loop_is_python_controls_feedback_with_the_filter():
    """`twv.linearize(speed=, steer_gains=, steer_filter=tau)` on Browser at 3 m/s: the six
    poles are python-control's `feedback` of the closed-form plant with a controller that reads
    the rates through 1/(tau s + 1), and the classical phase margin is `stability_margins` of
    that loop; the lag costs phase margin against the unfiltered law."""
    control = pytest.importorskip("control")
    model = twv.Model("whipple", params=FOLDER / "browser.toml")
    gains = {"k_phi": 5.0, "k_delta": 0.0, "k_phi_dot": 15.0, "k_delta_dot": 0.0}
    tau = 0.01
    lin = twv.linearize(model, speed=3.0, steer_gains=gains, steer_filter=tau)
    plain = twv.linearize(model, speed=3.0, steer_gains=gains)
    st = lin.steer
    bench = benchmark_matrices(read_parameters(FOLDER / "browser.toml"))
    a = bench.state_matrix(3.0)
    b = np.zeros((4, 1))
    b[2:, 0] = np.linalg.inv(bench.M)[:, 1]
    plant = control.ss(a, b, np.eye(4), np.zeros((4, 1)))
    lag = control.ss(control.tf([1.0], [tau, 1.0]))
    # The law as a sum of SISO channels (MIMO transfer functions need slycot): a block
    # diagonal of (k_phi, k_delta, k_phi_dot lag, k_delta_dot lag) summed into one torque.
    channels = control.append(
        control.ss([], [], [], [[gains["k_phi"]]]),
        control.ss([], [], [], [[gains["k_delta"]]]),
        gains["k_phi_dot"] * lag,
        gains["k_delta_dot"] * lag,
    )
    law = control.ss([], [], [], np.ones((1, 4))) * channels
    closed = control.feedback(plant, law, sign=1)
    theirs = np.sort_complex(control.poles(closed))
    # k_delta_dot = 0 leaves one filter state unobserved: its pole (-1/tau) may or may not
    # be in python-control's realisation; twv keeps it.
    ours = np.sort_complex(np.asarray(st["poles"]))
    missing = [p for p in ours if np.min(np.abs(theirs - p)) > 1e-6 * max(1.0, abs(p))]
    assert len(ours) == 6 and len(missing) <= 1, (ours, theirs)
    for p in missing:
        assert abs(p - (-1.0 / tau)) < 1e-8 / tau, p
    for p in theirs:
        assert np.min(np.abs(ours - p)) < 1e-6 * max(1.0, abs(p)), (p, ours)
    _, pm, _, _, wgc, _ = control.stability_margins(-law * plant)
    m = st["margins"]
    assert m is not None
    assert abs(m["phase_margin"]["deg"] - pm) < 1e-3, (m, pm)
    assert abs(m["phase_margin"]["frequency"] - wgc) < 1e-3 * wgc
    assert m["phase_margin"]["deg"] < plain.steer["margins"]["phase_margin"]["deg"]
