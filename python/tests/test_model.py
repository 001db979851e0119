"""Model evaluation on batches: equal to single calls and to the CLI, bad input refused with a
message naming the argument, never a crash."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import REPO, cli_json

import twv


def states(n: int, nx: int, seed: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1.0, 1.0, (n, nx))


def test_f_on_a_million_states_equals_single_calls(vehicle8):
    x = states(1_000_000, 8)
    u = np.random.default_rng(2).uniform(-200, 200, (1_000_000, 2))
    batch = vehicle8.f(x, u)
    assert batch.shape == (1_000_000, 8)
    # The same bits as batches of other sizes (the work is split across threads and chunks)...
    chunks = np.concatenate(
        [vehicle8.f(x[k : k + 7919], u[k : k + 7919]) for k in range(0, len(x), 7919)]
    )
    assert np.array_equal(batch, chunks)
    # ...and as one call per state, at 20 000 states spread over the batch and its two ends
    # (a million single Python calls took 19 s of the suite and test nothing more).
    picks = np.unique(np.r_[0:1000, 999_000:1_000_000, np.linspace(0, 999_999, 18_000).astype(int)])
    single = np.array([vehicle8.f(x[i], u[i]) for i in picks])
    assert np.array_equal(batch[picks], single)


def test_jacobians_match_single_calls_and_finite_differences(vehicle8):
    x = states(50, 8)
    jx, ju = vehicle8.jac_x(x), vehicle8.jac_u(x)
    assert jx.shape == (50, 8, 8) and ju.shape == (50, 8, 2)
    assert np.array_equal(jx[7], vehicle8.jac_x(x[7]))
    # Central differences of f agree to O(h²).
    h = 1e-6
    for j in range(8):
        e = np.zeros(8)
        e[j] = h
        fd = (vehicle8.f(x + e) - vehicle8.f(x - e)) / (2 * h)
        assert np.allclose(fd, jx[:, :, j], rtol=1e-6, atol=1e-6)
    # J·v is the Jacobian times v.
    v = states(50, 8, seed=3)
    assert np.allclose(vehicle8.jw(x, v), np.einsum("nij,nj->ni", jx, v), rtol=1e-13, atol=1e-13)


def test_f_equals_cli_eval_for_shipped_and_ir(vehicle8):
    x = [0.3, 1.0, -2.0, 0.4, 0.2, -0.1, 0.05, 0.3]
    cli = cli_json("eval", "--x", ",".join(map(str, x)), "--u", "10,-3", "--jac", flag=False)
    assert vehicle8.f(x, [10, -3]).tolist() == cli["f"]
    assert vehicle8.jac_x(x, [10, -3]).tolist() == cli["jac_x"]
    ir, paper = REPO / "generated" / "ir" / "vehicle8.json", REPO / "vehicles" / "paper.toml"
    interpreted = twv.Model(ir=ir, params=paper, runtime="interpreter")
    jitted = twv.Model(ir=ir, params=paper)
    assert (interpreted.engine, jitted.engine) == ("interpreted", "jit")
    x, u, v = states(1000, 8), np.tile([10.0, -3.0], (1000, 1)), states(1000, 8)[::-1].copy()
    # Generated code, the interpreter and the JIT: the same bits.
    for model in (interpreted, jitted):
        assert np.array_equal(model.f(x, u), vehicle8.f(x, u))
        assert np.array_equal(model.jac_x(x, u), vehicle8.jac_x(x, u))
        assert np.array_equal(model.jw(x, v, u), vehicle8.jw(x, v, u))
    with pytest.raises(twv.InputError, match="runtime"):
        twv.Model(ir=ir, runtime="llvm")


def test_parameters_from_a_dict_a_file_or_toml(vehicle8, tmp_path):
    heavier = twv.Model("vehicle8", params={"m2": 10.0, "I2": [0.9, 0.9, 0.04]})
    assert heavier.params["m2"] == 10.0 and heavier.params["I2_yy"] == 0.9
    assert heavier.params["m1"] == vehicle8.params["m1"]
    x = states(10, 8)
    assert not np.array_equal(heavier.f(x), vehicle8.f(x))
    text = (REPO / "vehicles" / "paper.toml").read_text().replace("m2 = 8.0", "m2 = 10.0")
    (tmp_path / "p.toml").write_text(text)
    from_file = twv.Model("vehicle8", params=tmp_path / "p.toml")
    assert from_file.params["m2"] == 10.0


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda m: m.f(np.zeros(7)), "x: 7 columns; want 8"),
        (lambda m: m.f(np.zeros((2, 2, 8))), "x: 3-D array"),
        (lambda m: m.f([[0.0] * 7 + [math.nan]]), "x[0, 7] = NaN is not finite"),
        (lambda m: m.f(np.zeros(8), [1.0, math.inf]), "u[0, 1] = inf is not finite"),
        (lambda m: m.f(["a"] * 8), "x: not an array of numbers"),
        (lambda m: m.jw(np.zeros((3, 8)), np.zeros((2, 8))), "v: 2 rows for 3 states"),
        (lambda m: twv.Model("vehicle9"), "unknown model"),
        (lambda m: twv.Model("vehicle8", params={"m3": 1.0}), "unknown parameter `m3`"),
        (lambda m: twv.Model("vehicle8", params={"m1": 1e308}), "m1"),
        (lambda m: twv.Model("vehicle8", params={"I2": [1.0]}), "`I2` has 3 component(s)"),
        (lambda m: twv.Model(ir="/nonexistent.json"), "/nonexistent.json"),
        (lambda m: twv.lyapunov(m, [0.1] * 7), "x0"),
        (lambda m: twv.lyapunov(m, [0.1] * 8, h=-1.0), "h"),
        (lambda m: twv.lyapunov(m, [0.1] * 8, iterations=10**12), "iterations"),
        (lambda m: twv.simulate(m, t_end=math.nan), "t_end"),
        (lambda m: twv.tune(m, spec="dpm>=95"), "dpm"),
        (lambda m: twv.sweep(m, kp=(0, 1, 10**7), kd=(0, 1, 10**7)), "points"),
        (lambda m: twv.simulate(m, anti_windup="sometimes"), "anti_windup"),
    ],
)
def test_bad_input_is_a_twv_error_naming_it(vehicle8, call, message):
    with pytest.raises(twv.TwvError) as err:
        call(vehicle8)
    assert message in str(err.value)
    assert isinstance(err.value, ValueError)


def test_error_kinds(vehicle8):
    with pytest.raises(twv.InputError):
        vehicle8.f(np.zeros(3))
    with pytest.raises(twv.ModelError):
        twv.Model("vehicle9")
    with pytest.raises(twv.NumericalError):
        twv.lyapunov(twv.Model("lorenz"), [1e308, 1e308, 1e308])
