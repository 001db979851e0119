"""twv's models in other people's tools, checked with the real clients: FMPy (validation, model
exchange with its CVode, co-simulation, directional derivatives) on the FMUs `twv export --fmu`
writes, and CasADi's `external` on the library `twv export --casadi` writes (values,
Jacobians, and an optimal control problem solved by IPOPT against a CasADi-symbolic model of the
same vehicle)."""

from __future__ import annotations

import ctypes
import json
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, cli_json, twv_binary

import twv

fmpy = pytest.importorskip("fmpy")
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import FMU2Model  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

RING11 = REPO / "tests" / "data" / "ring11.json"


def export(out: Path, *args: str) -> dict:
    """`twv export ARGS --out OUT --json`, its result."""
    done = subprocess.run(
        [str(twv_binary()), "export", *args, "--out", str(out), "--json", "--quiet"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> dict[str, Path]:
    """The FMUs of vehicle8 (generated code), the bicycle (interpreter) and a user's IR."""
    out = tmp_path_factory.mktemp("fmus")
    made = {}
    for key, args in {
        "vehicle8": ["--model", "vehicle8"],
        "whipple": ["--model", "whipple"],
        "ring11": ["--ir", str(RING11)],
        "vehicle8_tunable": ["--model", "vehicle8", "--tunable", "--name", "v8_tunable"],
    }.items():
        result = export(out / key, "--fmu", *args)
        made[key] = out / key / result["file"]
        assert result["engine"] == ("interpreter" if key in ("whipple", "ring11") else "generated")
    return made


@pytest.mark.parametrize("key", ["vehicle8", "whipple", "ring11", "vehicle8_tunable"])
def test_fmpy_finds_no_problem_in_an_exported_fmu(fmus, key):
    assert validate_fmu(str(fmus[key])) == []
    md = fmpy.read_model_description(str(fmus[key]))
    assert md.fmiVersion == "2.0" and md.modelExchange and md.coSimulation
    assert md.coSimulation.providesDirectionalDerivative


def test_the_same_export_is_the_same_bytes(fmus, tmp_path):
    again = export(tmp_path, "--fmu", "--model", "vehicle8")
    assert (tmp_path / again["file"]).read_bytes() == fmus["vehicle8"].read_bytes()


def test_every_variable_has_the_irs_unit_and_description(fmus):
    md = fmpy.read_model_description(str(fmus["vehicle8"]))
    model = twv.Model("vehicle8")
    by_name = {v.name: v for v in md.modelVariables}
    for name in model.states:
        v = by_name[name]
        assert v.causality == "output" and v.unit == model.units[name] and v.description
        assert by_name[f"der({name})"].derivative is v
    for name in model.inputs:
        assert by_name[name].causality == "input" and by_name[name].unit == model.units[name]
    # Derivatives depend on what the Jacobians' sparsity says: der(x) on theta and v_x, v_y.
    der_x = next(u for u in md.derivatives if u.variable.name == "der(x)")
    assert sorted(d.name for d in der_x.dependencies) == ["theta", "v_x", "v_y"]


def co_simulation(fmu: Path, start: dict, t_end: float) -> np.ndarray:
    return fmpy.simulate_fmu(
        str(fmu),
        fmi_type="CoSimulation",
        start_values=start,
        stop_time=t_end,
        output_interval=0.01,
    )


def test_co_simulation_is_twv_ride_bit_for_bit(fmus):
    """The FMU's fmi2DoStep is twv's RK4 with the same 1 ms step: the same bits as `twv ride`
    (the study's vehicle, open loop, from a tilt under constant inputs)."""
    x0 = [0.1, 0, 0, 0, 0, 0, 0, 0]
    ride = cli_json(
        "ride",
        "--x0",
        ",".join(map(str, x0)),
        "--u",
        "20,0.5",
        "--t-end",
        "1",
        "--fall-angle",
        "inf",
        "--watch",
        "phi",
    )
    r = co_simulation(fmus["vehicle8"], {"phi": 0.1, "F1": 20.0, "T2": 0.5}, 1.0)
    assert r["time"][-1] == pytest.approx(1.0)
    assert abs(r["phi"][-1]) == ride["final_value"]


def test_co_simulation_of_the_bicycle_and_a_user_model_is_twv_ride(fmus):
    """The bicycle (interpreter) from its steady motion at 5 m/s with a push, and ring11."""
    ride = cli_json(
        "ride", "--model", "whipple", "--speed", "5", "--perturb", "w_phi=0.05", "--t-end", "1"
    )
    states = twv.Model("whipple").states
    start = dict(zip(states, ride["x0"], strict=True))
    r = co_simulation(fmus["whipple"], start, 1.0)
    # final_value is |watched state| at the end: the same bits (the interpreter is f's reference).
    assert abs(r["phi"][-1]) == ride["final_value"]
    ring = cli_json(
        "ride",
        "--ir",
        str(RING11),
        "--x0",
        "1,0,0,0,0,0,0,0,0,0,0",
        "--watch",
        "x0",
        "--t-end",
        "1",
    )
    r = co_simulation(fmus["ring11"], {"x0": 1.0}, 1.0)
    assert abs(r["x0"][-1]) == ring["final_value"]
    # x0' = -x0 + a x1 with x1 small: close to e^-1, a closed form the RK4 step resolves.
    assert abs(r["x0"][-1] - np.exp(-1.0)) < 1e-3


def test_model_exchange_with_fmpys_cvode_is_twv_dopri(fmus):
    """Model exchange through FMPy's own solver (CVode) agrees with twv's adaptive DOPRI."""
    ride = cli_json(
        "ride",
        "--x0",
        "0.1,0,0,0,0,0,0,0",
        "--u",
        "20,0.5",
        "--t-end",
        "1",
        "--fall-angle",
        "inf",
        "--integrator",
        "dopri",
        "--rtol",
        "1e-11",
        "--atol",
        "1e-13",
    )
    r = fmpy.simulate_fmu(
        str(fmus["vehicle8"]),
        fmi_type="ModelExchange",
        start_values={"phi": 0.1, "F1": 20.0, "T2": 0.5},
        stop_time=1.0,
        output_interval=0.01,
        relative_tolerance=1e-10,
    )
    assert abs(r["phi"][-1] - ride["final_value"]) < 1e-6


def numbers(v) -> str:
    """A vector as a command-line value, every digit kept."""
    return ",".join(repr(float(x)) for x in v)


def pointer(a: np.ndarray):
    """A float64 array as the `double*` FMPy's low-level calls take."""
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def instance(fmu: Path, tmp_path: Path) -> FMU2Model:
    md = fmpy.read_model_description(str(fmu))
    unzipdir = fmpy.extract(str(fmu), unzipdir=str(tmp_path / "unzip"))
    m = FMU2Model(
        guid=md.guid,
        unzipDirectory=unzipdir,
        modelIdentifier=md.modelExchange.modelIdentifier,
        instanceName="twv",
    )
    m.instantiate()
    m.setupExperiment(startTime=0.0)
    m.enterInitializationMode()
    m.exitInitializationMode()
    m.enterContinuousTimeMode()
    return m


def test_the_closed_loop_under_the_studys_pd_is_twv_simulate(fmus, tmp_path):
    """The study's PD closed around the FMU by its importer (FMPy's model-exchange API and
    scipy's DOP853) recovers from the study's tilt exactly as `twv simulate` does."""
    from scipy.integrate import solve_ivp

    sim = twv.simulate(twv.Model("vehicle8"), integrator="dopri", rtol=1e-11, atol=1e-13, t_end=2)
    gains = sim.raw["controller"]["pitch"]["gains"]
    kp, kd = gains["kp"], gains["kd"]
    assert sim.raw["controller"]["pitch"]["setpoint"] == {"kind": "sine", "amplitude": 0.03}
    m = instance(fmus["vehicle8"], tmp_path)
    nx = 8

    def rhs(_t, x):
        phi, w_y = x[0], x[4]
        force = kp * (phi - 0.03 * np.sin(phi)) + kd * w_y  # the study's setpoint 0.03 sin Φ
        m.setContinuousStates(pointer(np.ascontiguousarray(x, dtype=float)), nx)
        m.setReal([16, 17], [force, 0.0])
        dx = np.zeros(nx)
        m.getDerivatives(pointer(dx), nx)
        return dx

    x0 = np.array([0.1, 0, 0, 0, 0, 0, 0, 0], dtype=float)
    sol = solve_ivp(rhs, (0, 2), x0, method="DOP853", rtol=1e-11, atol=1e-13, t_eval=[2.0])
    m.terminate()
    m.freeInstance()
    assert sim.t[-1] == pytest.approx(2.0)
    assert abs(sol.y[0, -1] - sim.series["phi"][-1]) < 1e-8
    assert abs(sol.y[4, -1] - sim.series["w_y"][-1]) < 1e-7


def test_directional_derivatives_are_twvs_jacobians(fmus, tmp_path):
    rng = np.random.default_rng(7)
    m = instance(fmus["vehicle8"], tmp_path)
    states = list(range(8))
    derivatives = list(range(8, 16))
    for _ in range(5):
        x = rng.uniform(-1, 1, 8)
        u = rng.uniform(-50, 50, 2)
        m.setContinuousStates(pointer(x), 8)
        m.setReal([16, 17], list(u))
        ev = cli_json("evaluate", "--x", numbers(x), "--u", numbers(u), "--jac")
        a, b = np.array(ev["jac_x"]), np.array(ev["jac_u"])
        for j in range(8):
            seed = np.eye(8)[j]
            col = m.getDirectionalDerivative(derivatives, states, list(seed))
            assert np.array_equal(np.array(col), a[:, j])
        for k in range(2):
            col = m.getDirectionalDerivative(derivatives, [16 + k], [1.0])
            assert np.array_equal(np.array(col), b[:, k])
        dx = np.zeros(8)
        m.getDerivatives(pointer(dx), 8)
        assert np.array_equal(dx, np.array(ev["f"]))
    m.terminate()
    m.freeInstance()


def test_tunable_parameters_change_the_equations(fmus, tmp_path):
    """With --tunable, a parameter is a variable: a heavier pendulum bar changes ẋ as twv does
    with the same value."""
    md = fmpy.read_model_description(str(fmus["vehicle8_tunable"]))
    params = [v for v in md.modelVariables if v.causality == "parameter"]
    assert {p.name for p in params} >= {"m2", "b", "g"} and all(
        p.variability == "tunable" for p in params
    )
    m2 = next(p for p in params if p.name == "m2")
    r = fmpy.simulate_fmu(
        str(fmus["vehicle8_tunable"]),
        fmi_type="CoSimulation",
        start_values={"phi": 0.1, "m2": 2 * float(m2.start)},
        stop_time=0.2,
        output_interval=0.01,
    )
    heavier = tmp_path / "heavier.toml"
    text = (REPO / "vehicles" / "paper.toml").read_text()
    values = twv.Model("vehicle8").params
    import re

    heavier.write_text(re.sub(r"(?m)^m2\s*=.*$", f"m2 = {2 * values['m2']!r}", text))
    ride = cli_json(
        "ride",
        "--params",
        str(heavier),
        "--x0",
        "0.1,0,0,0,0,0,0,0",
        "--t-end",
        "0.2",
        "--fall-angle",
        "inf",
    )
    assert abs(r["phi"][-1]) == ride["final_value"]
    # Refused: a derivative is calculated, a mass must be positive.
    m = instance(fmus["vehicle8_tunable"], tmp_path)
    with pytest.raises(FMICallException, match=r"status 3 \(error\)"):
        m.setReal([8], [1.0])
    with pytest.raises(FMICallException, match=r"status 3 \(error\)"):
        m.setReal([m2.valueReference], [-1.0])
    m.freeInstance()


# ---- CasADi ----

casadi = pytest.importorskip("casadi")


@pytest.fixture(scope="module")
def external(tmp_path_factory):
    out = tmp_path_factory.mktemp("casadi")
    result = export(out, "--casadi", "--model", "vehicle8")
    assert result["file"] == "libtwv_vehicle8.so"
    return casadi.external("f", str(out / result["file"]))


def test_the_external_function_is_twvs_f_and_jacobians(external):
    rng = np.random.default_rng(3)
    jac = external.jacobian()
    for _ in range(5):
        x, u = rng.uniform(-1, 1, 8), rng.uniform(-50, 50, 2)
        ev = cli_json("evaluate", "--x", numbers(x), "--u", numbers(u), "--jac")
        assert np.array_equal(np.array(external(x, u)).ravel(), np.array(ev["f"]))
        jx, ju = jac(x, u, 0)
        assert np.array_equal(np.array(jx), np.array(ev["jac_x"]))
        assert np.array_equal(np.array(ju), np.array(ev["jac_u"]))


def symbolic_vehicle8():
    """f(x, u) of vehicle8 as CasADi expressions (twv's own derivation, in CasADi symbols) with
    the study's parameter values substituted."""
    from twv_modeling.registry import build

    model = build("vehicle8")
    p = np.array([par.default for par in model.params])
    f = casadi.Function("f", [model.x, model.u, model.p], [model.expressions["f"]])
    x, u = casadi.SX.sym("x", 8), casadi.SX.sym("u", 2)
    return casadi.Function("f_sym", [x, u], [f(x, u, p)])


def tilt_recovery(f, n: int = 40, t: float = 2.0) -> tuple[float, np.ndarray, float]:
    """The minimum-effort recovery from the study's tilt in `t` s: ∫F² dt by direct multiple
    shooting (n intervals, one RK4 step each), upright and at rest at the end, solved by
    IPOPT. Returns the optimum, the force and the solve time [s]."""
    opti = casadi.Opti()
    x = opti.variable(8, n + 1)
    force = opti.variable(1, n)
    h = t / n

    def step(xk, uk):
        k1 = f(xk, uk)
        k2 = f(xk + h / 2 * k1, uk)
        k3 = f(xk + h / 2 * k2, uk)
        k4 = f(xk + h * k3, uk)
        return xk + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    for k in range(n):
        opti.subject_to(x[:, k + 1] == step(x[:, k], casadi.vertcat(force[k], 0)))
    opti.subject_to(x[:, 0] == [0.1, 0, 0, 0, 0, 0, 0, 0])
    opti.subject_to(x[0, n] == 0)
    opti.subject_to(x[4, n] == 0)
    opti.subject_to(x[5, n] == 0)
    opti.minimize(h * casadi.sumsqr(force))
    opti.solver(
        "ipopt",
        {"print_time": False},
        {"print_level": 0, "tol": 1e-10, "hessian_approximation": "limited-memory"},
    )
    start = time.perf_counter()
    sol = opti.solve()
    took = time.perf_counter() - start
    return float(sol.value(opti.f)), np.array(sol.value(force)).ravel(), took


def test_an_optimal_control_problem_has_the_same_optimum_with_the_external_function(external):
    ext_cost, ext_force, ext_time = tilt_recovery(external)
    sym_cost, sym_force, sym_time = tilt_recovery(symbolic_vehicle8())
    print(
        f"\nminimum-effort tilt recovery over 2 s (IPOPT, 40 intervals): "
        f"twv external {ext_cost:.9g} N² s in {ext_time:.3f} s, "
        f"CasADi symbolic {sym_cost:.9g} N² s in {sym_time:.3f} s"
    )
    assert ext_cost == pytest.approx(sym_cost, rel=1e-7)
    assert np.allclose(ext_force, sym_force, rtol=1e-5, atol=1e-3)
    # The effort is real: a recovery from 0.1 rad needs a force of the order of Kp·Φ.
    assert 10 < np.abs(ext_force).max() < 1e4


# ---- python-control ----


def test_python_controls_margins_are_twvs(vehicle8):
    """The pitch loop broken at the force input, L(s) = −K (sI − A)⁻¹ b, built by python-control
    from the exported (A, B, C, D): its phase margin and crossover, and the lower gain margin
    1/|L(0)| of the open-loop unstable plant, equal twv's."""
    control = pytest.importorskip("control")
    lin = twv.linearize(vehicle8)
    a, b, c, d = lin.state_space()
    assert c.shape == (8, 8) and d.shape == (8, 2)
    g = lin.raw["gains"]
    k = np.zeros((1, 8))
    k[0, 0], k[0, 4] = g["kp"], g["kd"]
    loop = control.ss(a, b[:, [0]], -k, 0)
    gm, pm, _, wcp = control.margin(loop)
    m = lin.raw["pitch"]["margins"]
    assert pm == pytest.approx(m["phase_margin"]["deg"], rel=1e-9)
    assert wcp == pytest.approx(m["phase_margin"]["frequency"], rel=1e-9)
    assert np.isinf(gm) and m["gain_margin_upper"] is None
    # A is singular (x, y, θ and the speeds are free at the upright), but Φ and Φ̇, the only
    # states K reads, depend on no other state: their 2 × 2 loop has the same L(s) and a
    # finite L(0).
    keep, others = [0, 4], [1, 2, 3, 5, 6, 7]
    assert not a[np.ix_(keep, others)].any()
    reduced = control.ss(a[np.ix_(keep, keep)], b[keep, :1], -k[:, keep], 0)
    low = 1 / abs(control.evalfr(reduced, 0))
    assert low == pytest.approx(m["gain_margin_lower"], rel=1e-9)
    assert m["delay_margin"] == pytest.approx(np.radians(pm) / wcp, rel=1e-9)


# ---- from Python ----


def test_python_exports_the_clis_bytes_and_writes_a_jobs_files(fmus, tmp_path, monkeypatch):
    """`twv.export(..., out=DIR)` with the runtime named in TWV_EXPORT_RUNTIME (Python's
    executable is not twv's, so the runtime is not beside it) writes the CLI's FMU byte for byte;
    `out=` writes any job's files as `twv <job> --out DIR` does."""
    runtime = twv_binary().parent / "libtwv_export.so"
    monkeypatch.setenv("TWV_EXPORT_RUNTIME", str(runtime))
    r = twv.export(twv.Model("vehicle8"), format="fmu", out=tmp_path / "py")
    assert r.raw["file"] == "twv_vehicle8.fmu"
    assert (tmp_path / "py" / "twv_vehicle8.fmu").read_bytes() == fmus["vehicle8"].read_bytes()
    twv.simulate(twv.Model("vehicle8"), t_end=0.5, out=tmp_path / "sim")
    subprocess.run(
        [
            str(twv_binary()),
            "simulate",
            "--t-end",
            "0.5",
            "--out",
            str(tmp_path / "cli"),
            "--quiet",
        ],
        check=True,
        capture_output=True,
    )
    py_files = sorted(p.name for p in (tmp_path / "sim").iterdir())
    assert py_files == sorted(p.name for p in (tmp_path / "cli").iterdir()) and py_files
    for name in py_files:
        if name.endswith(".csv"):
            assert (tmp_path / "sim" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    monkeypatch.setenv("TWV_EXPORT_RUNTIME", str(tmp_path / "nowhere.so"))
    with pytest.raises(twv.InputError, match="nowhere.so"):
        twv.export(twv.Model("vehicle8"), format="fmu", out=tmp_path / "none")
    assert not (tmp_path / "none").exists()
