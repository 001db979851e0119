"""Physics every correct vehicle model satisfies (docs/src/conventions.md), checked on the derived
equations for both parameter files."""

import casadi as ca
import numpy as np
import pytest
from conftest import numeric, param, random_states

from twv_modeling.registry import build


def _pitch_constants(name, params):
    m2, b, I2y = param(params, "m2"), param(params, "b"), param(params, "I2_yy")
    if name == "segway7":
        Mx = m2 + 2 * param(params, "m_w") + 2 * param(params, "J_a") / param(params, "R") ** 2
    else:
        Mx = param(params, "m1") + m2
    Ip = I2y + m2 * b * b
    lam2 = m2 * param(params, "g") * b * Mx / (Ip * Mx - m2 * m2 * b * b)
    return Mx, Ip, lam2


def test_upright_and_hanging_eigenvalues(vehicle, params):
    lam = np.sqrt(_pitch_constants(vehicle.model.name, params)[2])
    zero_u = np.zeros(vehicle.nu)
    up = np.linalg.eigvals(vehicle("jac_x", np.zeros(vehicle.nx), zero_u, params))
    up = up[np.argsort(-up.real)]
    assert np.isclose(up[0].real, lam, rtol=1e-12) and np.isclose(up[-1].real, -lam, rtol=1e-12)
    assert np.all(np.abs(up[1:-1]) < 1e-9 * lam)
    hanging = np.zeros(vehicle.nx)
    hanging[0] = np.pi
    down = np.linalg.eigvals(vehicle("jac_x", hanging, zero_u, params))
    down = down[np.argsort(-down.imag)]
    assert np.isclose(down[0].imag, lam, rtol=1e-12) and np.isclose(down[-1].imag, -lam, rtol=1e-12)
    assert np.all(np.abs(down.real) < 1e-9 * lam)


def _simulate(vehicle, x0, u, params, t_end, with_work=False):
    """CVODES at tight tolerance; optionally integrate the input power Q.p alongside."""
    m = vehicle.model
    ns = m.expressions["M"].size1()
    f = ca.substitute(m.expressions["f"], ca.vertcat(m.u, m.p), ca.DM(np.concatenate([u, params])))
    power = ca.substitute(
        ca.dot(m.expressions["Q"], m.x[-ns:]),
        ca.vertcat(m.u, m.p),
        ca.DM(np.concatenate([u, params])),
    )
    work = ca.SX.sym("work")
    ode = ca.vertcat(f, power) if with_work else f
    state = ca.vertcat(m.x, work) if with_work else m.x
    integ = ca.integrator(
        "sim",
        "cvodes",
        {"x": state, "ode": ode},
        0.0,
        t_end,
        {"abstol": 1e-13, "reltol": 1e-13, "max_num_steps": 200000},
    )
    start = np.concatenate([x0, [0.0]]) if with_work else x0
    return np.array(integ(x0=start)["xf"]).squeeze()


def _energy(vehicle, x, params):
    return float(vehicle("energy", x, np.zeros(vehicle.nu), params))


def test_energy_conserved_without_input(vehicle, params):
    xs, _ = random_states(vehicle, 2, seed=11)
    for x0 in xs:
        xf = _simulate(vehicle, x0, np.zeros(vehicle.nu), params, 5.0)
        e0, ef = _energy(vehicle, x0, params), _energy(vehicle, xf, params)
        # Relative to the energy's scale (T + V can be near zero by cancellation).
        scale = abs(e0) + param(params, "m2") * param(params, "g") * param(params, "b")
        assert abs(ef - e0) <= 1e-9 * scale


def test_energy_change_equals_input_work(vehicle, params):
    xs, us = random_states(vehicle, 2, seed=12)
    for x0, u in zip(xs, us, strict=True):
        out = _simulate(vehicle, x0, u, params, 2.0, with_work=True)
        xf, work = out[:-1], out[-1]
        change = _energy(vehicle, xf, params) - _energy(vehicle, x0, params)
        assert abs(change - work) <= 1e-9 * max(abs(work), abs(_energy(vehicle, x0, params)))


def test_base_height_does_not_enter_dynamics(vehicle, params):
    m = vehicle.model
    a = m.p[[p.name for p in m.params].index("a")]
    assert not ca.depends_on(m.expressions["f"], a)
    xs, us = random_states(vehicle, 10)
    other = params.copy()
    other[[p.name for p in m.params].index("a")] = 7.0
    for x, u in zip(xs, us, strict=True):
        assert np.array_equal(vehicle("f", x, u, params), vehicle("f", x, u, other))


LATERAL = ("y", "theta", "v_y", "w_z")


def _lateral_indices(vehicle):
    names = [s.name for s in vehicle.model.states]
    return [names.index(n) for n in LATERAL if n in names]


def _mirror_input(vehicle, u):
    if vehicle.model.name == "segway7":
        return u[::-1].copy()  # swap left and right wheel torques
    return u * np.array([1.0, -1.0])


def test_mirror_symmetry(vehicle, params):
    lat = _lateral_indices(vehicle)
    xs, us = random_states(vehicle, 30)
    for x, u in zip(xs, us, strict=True):
        xm = x.copy()
        xm[lat] *= -1
        fm = vehicle("f", xm, _mirror_input(vehicle, u), params)
        expected = vehicle("f", x, u, params)
        expected[lat] *= -1
        assert np.allclose(fm, expected, rtol=1e-13, atol=1e-13 * np.abs(expected).max())


def test_planar_motion_stays_planar_and_is_a_cart_pendulum(vehicle, params):
    lat = _lateral_indices(vehicle)
    Mx, Ip, _ = _pitch_constants(vehicle.model.name, params)
    m2, b, g = param(params, "m2"), param(params, "b"), param(params, "g")
    xs, us = random_states(vehicle, 30)
    i_phi, i_wy, i_vx = (vehicle.state_index(n) for n in ("phi", "w_y", "v_x"))
    for x, u in zip(xs, us, strict=True):
        x[lat] = 0.0
        u = _mirror_input(vehicle, u) * 0.5 + u * 0.5  # symmetric input: T2 = 0 or tau_L = tau_R
        fx = vehicle("f", x, u, params)
        assert np.all(fx[lat] == 0.0)
        # Cart-pendulum: [Ip, m l cos; m l cos, Mx] [wy', vx'] = [m g l sin + tau, F + m l sin wy^2]
        phi, wy = x[i_phi], x[i_wy]
        c, s = np.cos(phi), np.sin(phi)
        if vehicle.model.name == "segway7":
            torque, force = -u.sum(), u.sum() / param(params, "R")
        else:
            torque, force = 0.0, u[0]
        A = np.array([[Ip, m2 * b * c], [m2 * b * c, Mx]])
        rhs = np.array([m2 * g * b * s + torque, force + m2 * b * s * wy * wy])
        acc = np.linalg.solve(A, rhs)
        assert np.allclose([fx[i_wy], fx[i_vx]], acc, rtol=1e-12, atol=1e-12 * np.abs(acc).max())


@pytest.mark.parametrize("file", ["paper.toml", "segway.toml"])
def test_vehicle8_momenta_conserved(file):
    from conftest import param_values

    v8 = numeric("vehicle8")
    params = np.array(param_values(file))
    m = build("vehicle8")
    rate = ca.Function(
        "rate", [m.x, m.u, m.p], [ca.jacobian(m.expressions["momentum"], m.x) @ m.expressions["f"]]
    )
    xs, _ = random_states(v8, 30)
    zero_u = np.zeros(2)
    for x in xs:
        scale = np.abs(v8("momentum", x, zero_u, params)).max() + 1.0
        assert np.all(np.abs(np.array(rate(x, zero_u, params))) < 1e-11 * scale)
    x0 = xs[0]
    xf = _simulate(v8, x0, zero_u, params, 3.0)
    p0, pf = v8("momentum", x0, zero_u, params), v8("momentum", xf, zero_u, params)
    assert np.allclose(p0, pf, rtol=1e-9, atol=1e-9 * np.abs(p0).max())


def test_constrained_models_do_not_conserve_momentum():
    """With the no-side-slip constraint the ground pushes sideways: the planar momentum changes.
    Guards against a momentum check that cannot fail."""
    from conftest import param_values

    v7 = numeric("vehicle7")
    params = np.array(param_values("paper.toml"))
    x0 = np.array([0.4, 0.0, 0.0, 0.0, 0.3, 1.0, 0.8])
    xf = _simulate(v7, x0, np.zeros(2), params, 1.0)
    p0, pf = v7("momentum", x0, np.zeros(2), params), v7("momentum", xf, np.zeros(2), params)
    assert np.abs(p0 - pf).max() > 1e-3
