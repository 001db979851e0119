"""From a description to an analysed model in one session: derived (CasADi) models, compiled at
run time (the JIT), run with exactly the bits of the shipped, compiled ones."""

from __future__ import annotations

import numpy as np

import twv
from twv import modeling


def test_derived_vehicle7_has_the_bits_of_the_shipped_one():
    derived = twv.derive("vehicle7")
    shipped = twv.Model("vehicle7")
    assert derived.engine == "jit" and shipped.engine == "generated"
    x = np.random.default_rng(4).uniform(-1, 1, (2000, 7))
    u = np.random.default_rng(5).uniform(-100, 100, (2000, 2))
    assert np.array_equal(derived.f(x, u), shipped.f(x, u))
    assert np.array_equal(derived.jac_x(x, u), shipped.jac_x(x, u))


def test_an_edited_multibody_vehicle_is_analysed_in_the_next_call():
    P, p_vec = modeling.vehicle_symbols()
    system = modeling.vehicles.vehicle8(P)
    # A heavier, longer pendulum bar: the upright's unstable pole must move.
    stock = twv.linearize(twv.derive(system, (P, p_vec)))
    edited = twv.linearize(twv.derive(system, (P, p_vec), params={"m2": 16.0, "b": 0.8}))
    pole = lambda r: max(m["eigenvalue"][0] for m in r.raw["open_loop"])  # noqa: E731
    assert abs(pole(stock) - 3.748070177901749) < 1e-9
    assert pole(edited) != pole(stock)


def test_an_explicit_model_from_python():
    m = modeling.ExplicitModel(
        "oscillator",
        states=[("q", "m"), ("p", "m/s")],
        params=[modeling.Param("k", "1/s^2", default=4.0, description="stiffness")],
    )
    q, p = m.x_parts
    (k,) = m.p_parts
    m.rhs = [p, -k * q]
    model = twv.derive(m)
    assert model.states == ["q", "p"]
    assert model.f([1.0, 0.0]).tolist() == [0.0, -4.0]
    # A harmonic oscillator's exponents are zero: the verdict says neutral or not converged,
    # never chaotic.
    s = twv.lyapunov(model, [1.0, 0.0], iterations=1000)
    assert np.all(np.abs(s.exponents) < 0.01)
    assert s.classification in ("neutral", "not_converged")
