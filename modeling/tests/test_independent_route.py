"""The constrained equations by a second, independent route: sympy's KanesMethod.

Kane's method builds the equations from partial velocities of the *constrained* system, with the
constraints given as dependent speeds, and shares nothing with the Hamel derivation in
twv_modeling.multibody. Agreement at random states to 1e-12 checks the derivation, and in
particular the gyroscopic terms that a naive substitution of v_y = 0 into the Lagrangian drops.
"""

import functools

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me
from conftest import numeric, param_values, random_states

from twv_modeling.params import VEHICLE_PARAMS

P = {p.name: sm.Symbol(p.name) for p in VEHICLE_PARAMS}


def _common():
    phi, x, y, th = me.dynamicsymbols("phi x y theta")
    wy, vx, vy, wz = me.dynamicsymbols("w_y v_x v_y w_z")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    B = A.orientnew("B", "Axis", (phi, A.y))
    A.set_ang_vel(N, wz * N.z)
    B.set_ang_vel(A, wy * A.y)
    O = me.Point("O")
    O.set_vel(N, 0)
    kd = [
        phi.diff() - wy,
        x.diff() - (vx * sm.cos(th) - vy * sm.sin(th)),
        y.diff() - (vx * sm.sin(th) + vy * sm.cos(th)),
        th.diff() - wz,
    ]
    return (phi, x, y, th), (wy, vx, vy, wz), N, A, B, O, kd


def _pendulum(H, B, N):
    Gp = H.locatenew("Gp", P["b"] * B.z)
    Gp.v2pt_theory(H, N, B)
    inertia = me.inertia(B, P["I2_xx"], P["I2_yy"], P["I2_zz"])
    return Gp, me.RigidBody("pendulum", Gp, B, P["m2"], (inertia, Gp))


def _study(constrained):
    q, (wy, vx, vy, wz), N, A, B, O, kd = _common()
    H = O.locatenew("H", q[1] * N.x + q[2] * N.y)
    H.set_vel(N, vx * A.x + vy * A.y)
    Gb = H.locatenew("Gb", P["a"] * N.z)
    Gb.v2pt_theory(H, N, A)
    base = me.RigidBody(
        "base", Gb, A, P["m1"], (me.inertia(A, P["I1_xx"], P["I1_yy"], P["I1_zz"]), Gb)
    )
    Gp, pend = _pendulum(H, B, N)
    F1, T2 = sm.symbols("F1 T2")
    g = P["g"]
    loads = [(Gb, -P["m1"] * g * N.z + F1 * A.x), (Gp, -P["m2"] * g * N.z), (A, T2 * N.z)]
    if constrained:
        kane = me.KanesMethod(
            N,
            q_ind=list(q),
            u_ind=[wy, vx, wz],
            kd_eqs=kd,
            u_dependent=[vy],
            velocity_constraints=[vy],
        )
        speeds = [wy, vx, wz]
    else:
        kane = me.KanesMethod(N, q_ind=list(q), u_ind=[wy, vx, vy, wz], kd_eqs=kd)
        speeds = [wy, vx, vy, wz]
    kane.kanes_equations([base, pend], loads)
    return kane, list(q), speeds, [vy] if constrained else [], [F1, T2]


def _segway():
    q, (wy, vx, vy, wz), N, A, B, O, kd = _common()
    R, c, mw, Ja, Jd = P["R"], P["c"], P["m_w"], P["J_a"], P["J_d"]
    psiL, psiR = me.dynamicsymbols("psi_L psi_R")
    wL, wR = me.dynamicsymbols("omega_L omega_R")
    H = O.locatenew("H", q[1] * N.x + q[2] * N.y + R * N.z)
    H.set_vel(N, vx * A.x + vy * A.y)
    Gp, pend = _pendulum(H, B, N)
    bodies, loads = [pend], [(Gp, -P["m2"] * P["g"] * N.z)]
    tau = sm.symbols("tau_L tau_R")
    for side, psi, w, t in ((1, psiL, wL, tau[0]), (-1, psiR, wR, tau[1])):
        W = A.orientnew(f"W{side}", "Axis", (psi, A.y))
        W.set_ang_vel(A, w * A.y)
        C = H.locatenew(f"C{side}", side * c / 2 * A.y)
        C.v2pt_theory(H, N, A)
        bodies.append(me.RigidBody(f"wheel{side}", C, W, mw, (me.inertia(W, Jd, Ja, Jd), C)))
        loads += [(C, -mw * P["g"] * N.z), (W, t * A.y), (B, -t * A.y)]
    kd += [psiL.diff() - wL, psiR.diff() - wR]
    rolling = [vy, wL - (vx - c / 2 * wz) / R, wR - (vx + c / 2 * wz) / R]
    kane = me.KanesMethod(
        N,
        q_ind=[*q, psiL, psiR],
        u_ind=[wy, vx, wz],
        kd_eqs=kd,
        u_dependent=[vy, wL, wR],
        velocity_constraints=rolling,
    )
    kane.kanes_equations(bodies, loads)
    dep = {vy: 0, wL: (vx - c / 2 * wz) / R, wR: (vx + c / 2 * wz) / R}
    # The wheel angles are ignorable: they appear only as sin^2 + cos^2, so any value will do.
    dep.update({psiL: 0.3, psiR: -1.1})
    return kane, list(q), [wy, vx, wz], dep, list(tau)


@functools.cache
def kane_rhs(name):
    """A numeric function (x, u, p) -> x_dot from Kane's equations."""
    if name == "segway7":
        kane, q, speeds, dep, inputs = _segway()
    else:
        kane, q, speeds, deps, inputs = _study(name == "vehicle7")
        dep = dict.fromkeys(deps, 0)
    # For dependent speeds sympy appends the velocity constraints: the unknowns are the
    # independent speed derivatives followed by the dependent ones.
    Mk = kane.mass_matrix.subs(dep)
    Fk = kane.forcing.subs(dep)
    th = q[3]
    vx = speeds[1]
    vy = 0 if name != "vehicle8" else speeds[2]
    wz = speeds[-1]
    qdot = [speeds[0], vx * sm.cos(th) - vy * sm.sin(th), vx * sm.sin(th) + vy * sm.cos(th), wz]
    args = [*q, *speeds, *inputs, *P.values()]
    return sm.lambdify(args, [Mk, Fk, qdot], "numpy")


@pytest.mark.parametrize("name", ["vehicle8", "vehicle7", "segway7"])
@pytest.mark.parametrize("file", ["paper.toml", "segway.toml"])
def test_hamel_derivation_matches_kane(name, file):
    model = numeric(name)
    params = np.array(param_values(file))
    fn = kane_rhs(name)
    xs, us = random_states(model, 25, seed=3)
    for x, u in zip(xs, us, strict=True):
        Mk, Fk, qdot = fn(*x, *u, *params)
        pdot = np.linalg.solve(np.array(Mk, dtype=float), np.array(Fk, dtype=float).ravel())
        expected = np.concatenate([np.array(qdot, dtype=float), pdot[: model.nx - 4]])
        got = model("f", x, u, params)
        assert np.allclose(got, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
