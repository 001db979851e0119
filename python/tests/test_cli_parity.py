"""Every analysis from Python equals the CLI's JSON for the same inputs, bit for bit (JSON
numbers are shortest round-trip decimals, so equal dicts mean equal doubles)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import REPO, cli_json, cli_shard

import twv

X0 = [0.1, 0, 0, 0, 0, 0, 0, 0]
X0_ARG = "0.1,0,0,0,0,0,0,0"
IR7 = REPO / "generated" / "ir" / "vehicle7.json"


def test_spectrum_shipped(vehicle8, tmp_path):
    # --out records the running estimates, as the Python call does by default.
    cli = cli_json(
        "lyap", "--model", "vehicle8", "--preset", "paper", "--x0", X0_ARG, "--out", str(tmp_path)
    )
    py = twv.lyapunov_spectrum(vehicle8, X0, preset="paper")
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
    py = twv.lyapunov_spectrum(
        model,
        [0.05, 0, 0, 0, 0, 0, 0],
        controller=twv.pid(3000, 1500, 100, f_max=400),
        integrator_kind="dopri",
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
    py = twv.disturb(vehicle8, direction, 0.15)
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
        X0,
        controller=twv.pid(3860, 1980, 50, v_loop=(0.08, 0.03), v_ref=0.5, yaw_kp=20, yaw_ref=0.1),
        t_end=6,
    )
    assert py.raw["end"] == cli["end"] and py.raw["metrics"] == cli["metrics"]
    assert {k: v for k, v in py.raw.items() if k not in ("title", "scenario")} == {
        k: v for k, v in cli.items() if k not in ("title", "scenario")
    }


def test_linear_margins_lqr(vehicle8):
    cli = cli_json("linear", "--gains", "3000,0,1200", "--actuator-lag", "0.01", "--delay", "0.005")
    py = twv.linearize(vehicle8, gains=(3000, 0, 1200), lag=0.01, delay=0.005)
    assert py.raw == cli
    assert (
        twv.margins(vehicle8, gains=(3000, 0, 1200), lag=0.01, delay=0.005)
        == cli["pitch"]["margins"]
    )


@pytest.mark.parametrize("spec", ["dpm>=60", "dgm>=6dB,ms<=2"])
def test_tune(vehicle8, spec):
    cli = cli_json("tune", "--spec", spec)
    py = twv.tune(vehicle8, spec)
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
    with pytest.raises(twv.InputError, match="not both"):
        twv.audit(model, hand=bad, hand_text=text)


def test_the_bicycles_speed_sweep():
    cli = cli_json("linear", "--model", "whipple", "--speed", "0:10:0.5")
    py = twv.steady_motion(twv.Model("whipple"), (0, 10, 0.5))
    assert py.raw == cli
    assert py.raw["verdict"] == "self_stable"
    [(weave, capsize)] = py.raw["stable_ranges"]
    assert abs(weave - 4.29238253634111) <= 1e-10 and abs(capsize - 6.02426201538837) <= 1e-10


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
        params={"m2": (4, 20, 3), "b": (0.3, 0.9, 2)},
        metric="spectral-abscissa",
    )
    assert py.points == shard["points"]
    assert py.value.shape == (2, 3, 1, 1, 9)
    assert list(py.params) == ["m2", "b"] and py.params["m2"].tolist() == [4.0, 12.0, 20.0]
    # The boundary moves to higher Kp with the heavier pendulum: fewer stable points.
    stable = (py.value < 0).sum(axis=(2, 3, 4))
    assert (np.diff(stable, axis=1) <= 0).all()
