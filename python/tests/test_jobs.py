"""Every job from Python is the registry's job: the same name as the CLI's subcommand, the
library's defaults in its signature, and the CLI's JSON for the same inputs, bit for bit (JSON
numbers are shortest round-trip decimals, so equal dicts mean equal doubles)."""

from __future__ import annotations

import ast
import inspect
import json
import os
import subprocess

import numpy as np
import pytest
from conftest import REPO, cli_json, cli_shard, twv_binary

import twv

X0 = [0.1, 0, 0, 0, 0, 0, 0, 0]
X0_ARG = "0.1,0,0,0,0,0,0,0"
IR7 = REPO / "generated" / "ir" / "vehicle7.json"


def test_spectrum_shipped(vehicle8, tmp_path):
    # --out records the running estimates, as the Python call does by default.
    cli = cli_json(
        "lyap", "--model", "vehicle8", "--preset", "paper", "--x0", X0_ARG, "--out", str(tmp_path)
    )
    py = twv.lyapunov(vehicle8, X0, preset="paper")
    assert py.raw == cli
    # The running estimates are the CLI's running.csv, to the last bit.
    csv = np.loadtxt(tmp_path / "running.csv", delimiter=",", skiprows=1)
    assert np.array_equal(py.running, csv[:, 1:9])
    assert np.array_equal(py.t, csv[:, 0])


def test_spectrum_interpreted_ir_closed_loop_dopri():
    model = twv.Model(ir=IR7)
    assert model.engine == "jit"
    cli = cli_json(
        "lyap",
        "--ir",
        str(IR7),
        "--x0",
        "0.05,0,0,0,0,0,0",
        "--gains",
        "3000,100,1500",
        "--f-max",
        "400",
        "--integrator",
        "dopri",
        "--rtol",
        "1e-8",
        "--iterations",
        "30",
        "--k",
        "3",
        "--seed",
        "7",
    )
    py = twv.lyapunov(
        model,
        [0.05, 0, 0, 0, 0, 0, 0],
        gains=twv.Gains(kp=3000, kd=1500, ki=100),
        f_max=400,
        integrator="dopri",
        rtol=1e-8,
        iterations=30,
        k=3,
        seed=7,
        running=False,
    )
    assert py.raw == cli


@pytest.mark.parametrize("direction", ["forward", "backward"])
def test_disturb(vehicle8, direction):
    cli = cli_json("disturb", "--direction", direction, "--tilt", "0.15")
    py = twv.disturb(vehicle8, direction=direction, tilt=0.15)
    assert py.raw == cli
    assert py.recovered == (cli["recovery"] == "recovered")


def test_sim_with_outer_loops(vehicle8):
    cli = cli_json(
        "sim",
        "--x0",
        X0_ARG,
        "--gains",
        "3860,50,1980",
        "--v-loop",
        "0.08,0.03",
        "--v-ref",
        "0.5",
        "--yaw-kp",
        "20",
        "--yaw-ref",
        "0.1",
        "--t-end",
        "6",
    )
    py = twv.simulate(
        vehicle8,
        x0=X0,
        gains={"kp": 3860, "ki": 50, "kd": 1980},
        v_loop={"kp": 0.08, "ki": 0.03},
        v_ref=0.5,
        yaw_kp=20,
        yaw_ref=0.1,
        t_end=6,
    )
    assert py.raw == cli


def test_linear_margins_lqr(vehicle8):
    cli = cli_json("linear", "--gains", "3000,0,1200", "--actuator-lag", "0.01", "--delay", "0.005")
    gains = twv.Gains(kp=3000, kd=1200)
    py = twv.linearize(vehicle8, gains=gains, lag=0.01, delay=0.005)
    assert py.raw == cli
    assert twv.margins(vehicle8, gains=gains, lag=0.01, delay=0.005) == cli["pitch"]["margins"]
    assert twv.margins(vehicle8, kp=3000, kd=1200, lag=0.01, delay=0.005) == py.margins


@pytest.mark.parametrize("spec", ["dpm>=60", "dgm>=6dB,ms<=2"])
def test_tune(vehicle8, spec):
    cli = cli_json("tune", "--spec", spec)
    py = twv.tune(vehicle8, spec=spec)
    assert py.raw == cli
    assert py.met == (cli["verdict"] == "met")


def test_audit():
    cli = cli_json("audit", "--model", "vehicle7", "--samples", "20")
    py = twv.audit(twv.Model("vehicle7"), samples=20)
    assert [py.raw] == cli or py.raw == cli


HAND7 = REPO / "examples" / "hand" / "vehicle7.toml"


def test_audit_of_a_hand_file(tmp_path):
    # The user's own hand model: the CLI's JSON, a file or its text.
    model = twv.Model("vehicle7")
    cli = cli_json("audit", "--hand", str(HAND7))
    py = twv.audit(model, hand=HAND7)
    assert py.raw == cli
    assert py.passed and not py.raw["disagreements"]
    # A planted error (the gyroscopic pair's half in Cp[v_x] dropped) fails the same way in
    # both, naming the entry and printing the dropped term.
    bad = tmp_path / "bad.toml"
    text = HAND7.read_text().replace("(w_y^2 + w_z^2)", "w_y^2")
    bad.write_text(text)
    cli = cli_json("audit", "--hand", str(bad))
    py = twv.audit(model, hand=bad)
    assert py.raw == cli
    assert not py.passed
    first = py.raw["disagreements"][0]
    assert first["label"] == "Cp[v_x]"
    assert first["difference"] == "m2*b*sin(phi)*w_z^2"
    from_text = twv.audit(model, hand_text=text)
    assert from_text.raw["disagreements"][0]["difference"] == "m2*b*sin(phi)*w_z^2"
    with pytest.raises(twv.InputError, match=r"hand file:\d+: \[Q\]: `v_y` is not one of"):
        twv.audit(model, hand_text=text.replace("[Q]", "[Q]\nv_y = 0"))
    with pytest.raises(twv.InputError, match="cannot be given with"):
        twv.audit(model, hand=bad, hand_text=text)


def test_the_bicycles_speed_sweep():
    cli = cli_json("steady", "--model", "whipple", "--speed", "0:10:0.5")
    py = twv.steady(twv.Model("whipple"), speed=(0, 10, 0.5))
    assert py.raw == cli
    assert py.raw["verdict"] == "self_stable"
    # Which bound is which is named, from the mode that crosses there.
    assert abs(py.weave_speed - 4.29238253634111) <= 1e-10
    assert abs(py.capsize_speed - 6.02426201538837) <= 1e-10
    assert py.stable_ranges == [(py.weave_speed, py.capsize_speed)]
    # Eigenvalues are complex, one row per speed; the table has their parts.
    assert py.eigenvalues.dtype == complex and py.eigenvalues.shape == (21, 4)
    weave_row = py.eigenvalues[np.argmin(np.abs(py.speeds - 4.5))]
    assert np.abs(weave_row.imag).max() > 1.0  # the weave oscillates
    table = py.to_pandas()
    assert list(table.columns[:3]) == ["speed", "re_1", "im_1"] and len(table) == 21


def test_sweep_equals_the_shard_file(vehicle8, tmp_path):
    points = {}
    for full in (False, True):
        shard = cli_shard(
            tmp_path / ("full" if full else "tail"),
            *("--kp", "0:8000:6", "--kd", "0:4000:5", "--metric", "max-lyapunov"),
            *(["--full-horizon"] if full else []),
        )
        py = twv.sweep(
            vehicle8, kp=(0, 8000, 6), kd=(0, 4000, 5), metric="max-lyapunov", full_horizon=full
        )
        assert len(py.to_pandas()) == 30
        assert py.points == shard["points"]
        assert py.value.shape == (1, 5, 6)
        # Statuses: a fall below the critical Kp, an exponent above it.
        assert (py.status[0, :, 0] == "fell").all()
        points[full] = py
    # The settled tail: taken by some loops, each λ1 within its tolerance of the full run.
    tail, full = points[False], points[True]
    assert np.isnan(full.settled_at).all()
    assert (~np.isnan(tail.settled_at)).sum() >= 5
    ok = ~np.isnan(full.value)
    assert (np.isnan(tail.value) == ~ok).all()
    assert np.abs(tail.value[ok] - full.value[ok]).max() <= twv.SETTLED_TAIL_TOLERANCE


def test_the_uncontrolled_bicycle_rides():
    args = ("--model", "whipple", "--perturb", "w_phi=0.05", "--t-end", "6")
    for speed, verdict in ((5.0, "recovered"), (3.0, "fell")):
        cli = cli_json("ride", *args, "--speed", str(speed), "--fall-angle", "0.5")
        py = twv.ride(
            twv.Model("whipple"), speed=speed, perturb={"w_phi": 0.05}, t_end=6.0, fall_angle=0.5
        )
        assert py.raw == cli
        assert py.verdict == verdict
        assert py.columns[:5] == ["t", "psi", "x", "y", "phi"]
        assert py.series["w_R"][0] == speed / 0.3


def test_a_sweep_over_parameters_equals_the_shard_file(vehicle8, tmp_path):
    shard = cli_shard(
        tmp_path,
        *("--kp", "0:4000:9", "--param", "m2=4:20:3", "--param", "b=0.3:0.9:2"),
        *("--metric", "spectral-abscissa"),
    )
    py = twv.sweep(
        vehicle8,
        kp=(0, 4000, 9),
        kd=(1980, 1980, 1),
        param={"m2": (4, 20, 3), "b": (0.3, 0.9, 2)},
        metric="spectral-abscissa",
    )
    assert py.points == shard["points"]
    assert py.value.shape == (2, 3, 1, 1, 9)
    assert list(py.params) == ["m2", "b"] and py.params["m2"].tolist() == [4.0, 12.0, 20.0]
    # The boundary moves to higher Kp with the heavier pendulum: fewer stable points.
    stable = (py.value < 0).sum(axis=(2, 3, 4))
    assert (np.diff(stable, axis=1) <= 0).all()


# --- one vocabulary: the registry's names, defaults, gains, parameters and typed results ---


def test_every_job_is_a_function_of_the_same_name_as_the_cli_subcommand():
    jobs = json.loads(twv._native.jobs())
    help_text = subprocess.run(
        [str(twv_binary()), "--help"], capture_output=True, text=True, check=True
    ).stdout
    for job in jobs:
        assert callable(getattr(twv, job["name"])), job["name"]
        # On the command line a `_` of a name is a `-` (`steer-map`).
        assert f"  {job['name'].replace('_', '-')} " in help_text, job["name"]
        for alias in job["aliases"]:
            if alias == "margins":
                continue  # twv.margins is the shortcut to linearize's margins
            assert getattr(twv, alias) is getattr(twv, job["name"]), alias
    assert twv.lyapunov_spectrum is twv.lyapunov and twv.steady_motion is twv.steady


def test_signatures_show_the_librarys_defaults():
    """The defaults a user sees (`help(twv.simulate)`) are the library's, and applying them
    changes nothing: the keyword defaults come from one `Settings::default()`."""
    for job in json.loads(twv._native.jobs()):
        name = job["name"]
        signature = inspect.signature(getattr(twv, name))
        # A value for each option the job cannot run without (a state).
        base = {o["name"]: [0.1, 0.0, 0.0] for o in job["options"] if o["required"]}
        defaults = twv.default_settings(name) | base
        assert twv.settings(name, **base) == defaults, name
        for option in job["options"]:
            parameter = signature.parameters[option["name"]]
            if option["required"]:
                assert parameter.default is inspect.Parameter.empty
                continue
            assert parameter.default == option["default"], (name, option["name"])
            if option["default"] is None or option["kind"] == "flag":
                continue
            given = base | {option["name"]: option["default"]}
            expected = defaults
            if "DOPRI" in option["help"] and option["name"] != "h":
                # DOPRI's options show the default that choosing DOPRI gives.
                expected = twv.settings(name, **base, integrator="dopri")
                given["integrator"] = "dopri"
            try:
                again = twv.settings(name, **given)
            except twv.InputError as e:
                # An option of a choice not taken (tracking_time without back-calculation,
                # v_ref without the velocity loop) shows the default that choice gives.
                conditional = ": needs " in str(e) or "belongs to" in str(e)
                assert conditional, (name, option["name"], str(e))
                continue
            assert again == expected, (name, option["name"])
        for option in job["options"]:
            assert option["help"] in getattr(twv, name).__doc__, (name, option["name"])


def test_no_default_is_written_in_the_python_package():
    """No function of the package restates a job's default: every keyword default in its
    source is None, False or a flag's off (the library holds the rest)."""
    allowed = {"ki"}  # twv.Gains: ki = 0 is what a PD law is, not a job's setting
    for path in (REPO / "python" / "twv").glob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.AnnAssign) and isinstance(node.value, ast.Constant):
                name = getattr(node.target, "id", "")
                if isinstance(node.value.value, float | int) and name not in allowed:
                    raise AssertionError(f"{path.name}:{node.lineno}: {name} = {node.value.value}")
            if isinstance(node, ast.FunctionDef | ast.Lambda):
                args = node.args
                for default in [*args.defaults, *args.kw_defaults]:
                    if default is None:
                        continue
                    value = getattr(default, "value", None)
                    numeric = isinstance(value, int | float) and not isinstance(value, bool)
                    assert not numeric, f"{path.name}:{node.lineno}: a numeric default {value}"


def test_gains_are_named_everywhere_and_a_tuple_is_refused(vehicle8):
    # The stumble: margins(m, gains=(3000, 900, 0)) meant Kd = 900 but ran Ki = 900.
    with pytest.raises(twv.InputError, match="not a list"):
        twv.margins(vehicle8, gains=(3000, 900, 0))
    named = twv.margins(vehicle8, gains=twv.Gains(kp=3000, kd=900))
    assert named == twv.margins(vehicle8, gains={"kp": 3000, "kd": 900})
    assert named == twv.margins(vehicle8, kp=3000, kd=900)
    assert named is not None and named["disk_alpha"] > 0
    # Tune's result is accepted wherever gains are.
    tuned = twv.tune(vehicle8, spec="dpm>=45")
    assert isinstance(tuned.gains, twv.Gains)
    assert twv.margins(vehicle8, gains=tuned) == twv.margins(vehicle8, gains=tuned.gains)
    with pytest.raises(twv.InputError, match="kpp"):
        twv.simulate(vehicle8, kpp=1)


def test_parameters_round_trip_in_both_vocabularies(vehicle8):
    # The stumble: Model("vehicle8", params=m.params) failed ("unknown parameter I1_xx").
    again = twv.Model("vehicle8", params=vehicle8.params)
    assert again.params == vehicle8.params
    by_key = twv.Model("vehicle8", params={"I2": [0.9, 0.8, 0.2]})
    by_name = twv.Model("vehicle8", params={"I2_xx": 0.9, "I2_yy": 0.8, "I2_zz": 0.2})
    assert by_key.params == by_name.params
    with pytest.raises(twv.InputError, match="twice"):
        twv.Model("vehicle8", params={"I2": [0.9, 0.8, 0.2], "I2_yy": 0.8})
    assert vehicle8.units["m2"] == "kg" and vehicle8.units["phi"] == "rad"
    assert vehicle8.units["F1"] == "N"


def test_results_are_data(vehicle8):
    lin = twv.linearize(vehicle8)
    # The LQR gain in its natural shape (inputs × states), not a column-major list.
    k = lin.lqr["k"]
    assert k.shape == (2, 4)
    assert lin.loop_poles.dtype == complex and (lin.loop_poles.real < 0).all()
    a, b, c, d = lin.state_space()
    assert a.shape == (8, 8) and b.shape == (8, 2) and c.shape == (8, 8) and d.shape == (8, 2)
    # A is ∂f/∂x at the upright: the model's own Jacobian there.
    assert np.array_equal(a, vehicle8.jac_x(np.zeros(8)))
    # The upright's open-loop eigenvalues ±λ and zeros.
    ev = lin.open_loop_eigenvalues
    assert np.isclose(ev.real.max(), -ev.real.min(), rtol=1e-9)
    sim = twv.simulate(vehicle8)
    assert "recovered" in repr(sim) and "peak 374.4 N" in repr(sim)
    assert sim.units["phi"] == "rad" and sim.units["F"] == "N" and sim.units["t"] == "s"
    frame = sim.to_pandas()
    assert list(frame.columns) == sim.columns and len(frame) == 1001


def test_the_linearisation_is_a_python_control_system(vehicle8):
    control = pytest.importorskip("control")
    lin = twv.linearize(vehicle8)
    sys = lin.to_control()
    assert sys.state_labels == vehicle8.states and sys.input_labels == vehicle8.inputs
    assert np.allclose(
        np.sort_complex(control.poles(sys)), np.sort_complex(lin.open_loop_eigenvalues)
    )
    # The pitch loop closed by python-control has twv's loop poles.
    g = lin.raw["gains"]
    plant = control.ss(*lin.state_space())
    k = np.zeros((2, 8))
    k[0, 0], k[0, 4] = g["kp"], g["kd"]  # F1 = Kp·Φ + Kd·Φ̇ (the study's PD, no setpoint feedback)
    closed = control.ss(plant.A + plant.B @ k, plant.B, plant.C, plant.D)
    poles = control.poles(closed)
    for p in lin.loop_poles:
        assert np.min(np.abs(poles - p)) < 1e-6 * max(1.0, abs(p)), p


def test_build_info_is_twv_version():
    info = twv.build_info()
    assert set(info) == {"version", "commit", "profile", "arch", "isa", "jit"}
    line = subprocess.run(
        [str(twv_binary()), "--version"], capture_output=True, text=True, check=True
    ).stdout
    assert info["version"] in line and info["commit"] in line and info["arch"] in line
    expected = os.environ.get("TWV_EXPECT_PROFILE")
    if expected:
        assert info["profile"] == expected, "the package the test command builds is a release build"
