"""The canonical forms of the derived coefficients (canonical.py): the same values as the raw
derivation, sin² + cos² = 1 applied (the pendulum's inertia about the hinge no longer depends on
the pitch), never more operations, and the operation counts of the issue "fewer operations from
the derivation" — f + ∂f/∂x no more than the hand formulation's."""

import casadi as ca
import numpy as np
import pytest

import twv_modeling.multibody as multibody
from twv_modeling.canonical import canonical_entry
from twv_modeling.hand_peer import vehicle8_by_hand
from twv_modeling.registry import build

COEFFICIENTS = ("M", "Cp", "F", "Q", "f")


@pytest.fixture(scope="module")
def raw_and_canonical():
    """vehicle8 derived with the rewrite switched off, and as shipped."""
    saved = multibody.canonical
    multibody.canonical = lambda m, params, env: m
    try:
        raw = build("vehicle8")
    finally:
        multibody.canonical = saved
    return raw, build("vehicle8")


def _function(model, name):
    return ca.Function(name, [model.x, model.u, model.p], [model.expressions[name]])


def _ops(model, e):
    return ca.Function("ops", [model.x, model.u, model.p], [ca.cse(e)]).n_instructions()


def test_values_are_the_raw_derivations(raw_and_canonical):
    raw, canon = raw_and_canonical
    rng = np.random.default_rng(11)
    p = [prm.default for prm in canon.params]
    for name in COEFFICIENTS:
        a, b = _function(raw, name), _function(canon, name)
        for _ in range(100):
            x = rng.uniform(-2, 2, canon.x.numel())
            u = rng.uniform(-100, 100, canon.u.numel())
            want, got = np.array(a(x, u, p)), np.array(b(x, u, p))
            scale = max(1.0, np.abs(want).max())
            assert np.abs(got - want).max() <= 1e-13 * scale, name


def test_the_hinge_inertia_no_longer_depends_on_the_pitch(raw_and_canonical):
    raw, canon = raw_and_canonical
    phi = canon.x[0]
    assert ca.depends_on(raw.expressions["M"][0, 0], raw.x[0])  # m2 (b² cos² + b² sin²) + I2_yy
    assert not ca.depends_on(canon.expressions["M"][0, 0], phi)  # m2 b² + I2_yy


def test_fewer_operations_and_no_more_than_by_hand(raw_and_canonical):
    raw, canon = raw_and_canonical
    for name in COEFFICIENTS:
        assert _ops(canon, canon.expressions[name]) <= _ops(raw, raw.expressions[name]), name
    f = canon.expressions["f"]
    f_jac = ca.vertcat(f, ca.vec(canon.jacobian_x()))
    hand = vehicle8_by_hand(canon)
    hand_jac = ca.vertcat(hand, ca.vec(ca.jacobian(hand, canon.x)))
    assert _ops(canon, f_jac) <= _ops(canon, hand_jac)
    assert _ops(canon, f) < _ops(raw, raw.expressions["f"])


def test_what_is_not_a_polynomial_is_kept():
    x, a = ca.SX.sym("x"), ca.SX.sym("a")
    env = {"x": x, "a": a}
    for e in (a / (x * x + 1) + a / (x * x + 1), ca.sin(2 * x) * ca.sin(2 * x)):
        assert ca.is_equal(canonical_entry(e, {"a"}, env), e)
    # ... and what is, is simplified: sin² + cos² = 1.
    s = ca.sin(x) * ca.sin(x) * a + ca.cos(x) * ca.cos(x) * a
    assert not ca.depends_on(canonical_entry(s, {"a"}, env), x)
