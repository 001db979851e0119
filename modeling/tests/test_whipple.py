"""The Whipple bicycle derived from bodies, joints and two rolling contacts (the contact
conditions generated from the wheels' geometry) against the published benchmark of Meijaard,
Papadopoulos, Ruina & Schwab (2007): its linearisation about upright straight running gives
their M, C1, K0, K2 (eq. 5.4), their Table 2 eigenvalues and their weave and capsize speeds;
the nonlinear equations conserve energy, and an uncontrolled bicycle recovers from a small lean
inside the self-stable speed range and not below it."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from test_whipple_benchmark import PUBLISHED, TABLE2, _expected

from twv_modeling.models.whipple import PARAM_NAMES, symbols, whipple
from twv_modeling.multibody import derive
from twv_modeling.whipple_benchmark import read_parameters

LATERAL_Q, LATERAL_P = ("phi", "delta"), ("w_phi", "w_delta")


class Bicycle:
    """The derived model, numerically: f, its Jacobian, M and the energy at the benchmark."""

    def __init__(self):
        P, p_vec = symbols()
        model = derive(whipple(P), P, p_vec)
        self.names = [s.name for s in model.states]
        self.values = read_parameters()
        self.p = [self.values[n] for n in PARAM_NAMES]
        e = model.expressions
        args = [model.x, model.u, model.p]
        self._f = ca.Function("f", args, [e["f"]])
        self._jac = ca.Function("jacobian", args, [ca.jacobian(e["f"], model.x)])
        self._mass = ca.Function("M", args, [e["M"]])
        self._energy = ca.Function("E", args, [e["energy"]])
        self.speeds = [s for s in self.names if s.startswith("w_")]

    def steady(self, v):
        """Upright straight running at speed v: only the rear wheel turns."""
        x = np.zeros(len(self.names))
        x[self.names.index("w_R")] = v / self.values["r_R"]
        return x

    def f(self, x):
        return np.array(self._f(x, [0, 0], self.p)).ravel()

    def energy(self, x):
        return float(self._energy(x, [0, 0], self.p))

    def lateral(self, v):
        """(M, A) of the lean and steer at speed v: M's (phi, delta) block and the Jacobian of
        (phi, delta, w_phi, w_delta)' with respect to them."""
        x = self.steady(v)
        jac = np.array(self._jac(x, [0, 0], self.p))
        idx = [self.names.index(n) for n in LATERAL_Q + LATERAL_P]
        m = np.array(self._mass(x, [0, 0], self.p))
        sp = [self.speeds.index(n) for n in LATERAL_P]
        return m[np.ix_(sp, sp)], jac[np.ix_(idx, idx)]

    def matrices(self):
        """M, C1, K0, K2 recovered from the linearisation at v = 0 and v = 1."""
        m, a0 = self.lateral(0.0)
        _, a1 = self.lateral(1.0)
        g = self.values["g"]
        k0 = -m @ a0[2:, :2] / g
        k2 = -m @ a1[2:, :2] - g * k0
        c1 = -m @ a1[2:, 2:]
        return {"M": m, "C1": c1, "K0": k0, "K2": k2}


@pytest.fixture(scope="module")
def bicycle():
    return Bicycle()


def test_the_state_is_the_benchmarks_plus_the_rolling_coordinates(bicycle):
    assert bicycle.names == ["psi", "x", "y", "phi", "theta", "delta", "w_phi", "w_R", "w_delta"]


def test_linearisation_equals_the_published_matrices(bicycle):
    got = bicycle.matrices()
    for name, want in PUBLISHED.items():
        want = np.array(want)
        zero = want == 0.0
        assert np.all(np.abs(got[name][zero]) <= 1e-12), name
        rel = np.abs(got[name][~zero] - want[~zero]) / np.abs(want[~zero])
        assert rel.max() <= 1e-12, (name, rel.max())


@pytest.mark.parametrize("speed", sorted(TABLE2))
def test_eigenvalues_equal_table_2(bicycle, speed):
    _, a = bicycle.lateral(float(speed))
    got, want = np.linalg.eigvals(a), _expected(TABLE2[speed])
    order = lambda z: z[np.lexsort((z.imag, z.real))]  # noqa: E731
    assert np.max(np.abs(order(got) - order(want))) <= 1e-10


def test_weave_and_capsize_speeds(bicycle):
    def abscissa(v):
        return float(np.max(np.linalg.eigvals(bicycle.lateral(v)[1]).real))

    weave = brentq(abscissa, 4.0, 5.0, xtol=1e-14, rtol=1e-15)
    capsize = brentq(abscissa, 5.5, 6.5, xtol=1e-14, rtol=1e-15)
    assert abs(weave - 4.29238253634111) <= 1e-10
    assert abs(capsize - 6.02426201538837) <= 1e-10


def _ride(bicycle, v, lean, t_end):
    """A free ride from upright running at v with roll rate `lean`, stopped if it falls
    (|phi| > 0.5 rad)."""
    x0 = bicycle.steady(v)
    x0[bicycle.names.index("w_phi")] = lean
    phi = bicycle.names.index("phi")

    def fallen(t, x):
        return 0.5 - abs(x[phi])

    fallen.terminal = True
    return solve_ivp(
        lambda t, x: bicycle.f(x),
        (0, t_end),
        x0,
        method="DOP853",
        rtol=1e-11,
        atol=1e-11,
        t_eval=np.linspace(0, t_end, 201),
        events=fallen,
    )


def test_energy_is_conserved_on_a_nonlinear_ride(bicycle):
    run = _ride(bicycle, 4.6, 0.5, 3.0)
    assert run.success
    e = [bicycle.energy(x) for x in run.y.T]
    assert max(abs(v - e[0]) for v in e) <= 1e-8 * abs(e[0])


def test_self_stable_inside_the_range_and_falling_below(bicycle):
    phi = bicycle.names.index("phi")
    # Inside the self-stable range a small push in lean dies out; below the weave speed it grows
    # into a fall (|phi| past 0.3 rad within 4 s), as the linear eigenvalues say.
    stable = _ride(bicycle, 5.0, 0.05, 8.0)
    assert stable.success and np.max(np.abs(stable.y[phi, -20:])) < 0.1 * np.max(
        np.abs(stable.y[phi])
    )
    falling = _ride(bicycle, 3.0, 0.05, 4.0)
    assert falling.status == 1, "the ride ended by falling"
    assert np.max(np.abs(falling.y[phi])) > 0.3


def _front_contact_height(values, x, names):
    """The front wheel's lowest point above the ground, from the state by plain geometry (numpy
    rotations, not the derivation): zero while the front wheel touches."""
    s = dict(zip(names, x, strict=True))

    def rot(axis, a):
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k

    lam, w, c = values["lambda"], values["w"], values["c"]
    r_r, r_f = values["r_R"], values["r_F"]
    r_nl = rot([0, 0, 1], s["psi"]) @ rot([1, 0, 0], s["phi"])
    r_nb = r_nl @ rot([0, 1, 0], s["theta"])
    rear_centre = np.array([s["x"], s["y"], 0.0]) + r_nl @ [0, 0, r_r]
    steer_point = rear_centre + r_nb @ [w + c, 0, -r_r]
    r_nh = r_nb @ rot([np.sin(lam), 0, -np.cos(lam)], s["delta"])
    front_centre = steer_point + r_nh @ [-c, 0, r_f]
    axle = r_nh @ [0, 1, 0]
    return front_centre[2] - r_f * np.sqrt(1 - axle[2] ** 2)


def test_the_front_wheel_stays_on_the_ground(bicycle):
    # The pitch is integrated from its rate (the derivative of the touching condition); the
    # geometry, computed independently, must find the front wheel on the ground all along a
    # ride with large lean and steer.
    run = _ride(bicycle, 4.6, 0.5, 3.0)
    heights = [_front_contact_height(bicycle.values, x, bicycle.names) for x in run.y.T]
    assert max(abs(h) for h in heights) <= 1e-9
    phi, delta = bicycle.names.index("phi"), bicycle.names.index("delta")
    assert np.max(np.abs(run.y[phi])) > 0.05 and np.max(np.abs(run.y[delta])) > 0.05
    # And the check bites: a pitch off by 1 mrad lifts the front wheel measurably.
    x = run.y[:, -1].copy()
    x[bicycle.names.index("theta")] += 1e-3
    assert abs(_front_contact_height(bicycle.values, x, bicycle.names)) > 1e-4
