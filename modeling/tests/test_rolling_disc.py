"""A thin disc rolling without slip on the ground, derived twice: with its rolling constraints in
the contact frame's speeds (v_x = R w_s, v_y = 0: coordinate-free coefficients) and in inertial
velocity components (x_dot = R w_s cos psi, y_dot = R w_s sin psi: coordinate-dependent, which
the derivation handles through the structure functions' derivative terms). Both must be the
same dynamics; energy is conserved; upright rolling is stable above the classical critical speed
v^2 = g R / 3 of a uniform thin disc."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from twv_modeling.derived import Signal
from twv_modeling.kinematics import Body, PlanarJoint, PrismaticJoint, RevoluteJoint
from twv_modeling.multibody import Constraint, MultibodySystem, derive
from twv_modeling.params import Param

VALUES = {"m": 1.5, "R": 0.3, "g": 9.81}


def _system(inertial: bool):
    P = {k: ca.SX.sym(k) for k in VALUES}
    m, r = P["m"], P["R"]
    diametral = m * r**2 / 4
    disc = Body("disc", "S", m, inertia=(diametral, m * r**2 / 2, diametral))
    lean = RevoluteJoint("L", "A", coord="phi", speed="w_phi", axis="x")
    spin = RevoluteJoint(
        "S", "L", coord="spin", speed="w_s", axis="y", at=(0, 0, r), axisymmetric=True
    )
    if inertial:
        joints = [
            PrismaticJoint("X", "N", coord="x", speed="v_X", axis="x"),
            PrismaticJoint("Y", "X", coord="y", speed="v_Y", axis="y"),
            RevoluteJoint("A", "Y", coord="psi", speed="w_psi", axis="z"),
            lean,
            spin,
        ]
        coords, speeds = ["x", "y", "psi", "phi", "spin"], ["v_X", "v_Y", "w_psi", "w_phi", "w_s"]
        constraints = (
            Constraint("v_X", lambda s: r * s["w_s"] * ca.cos(s["psi"]), "rolls along its heading"),
            Constraint("v_Y", lambda s: r * s["w_s"] * ca.sin(s["psi"]), "no side slip"),
        )
    else:
        planar = PlanarJoint("A", "N", coords=("psi", "x", "y"), speeds=("w_psi", "v_x", "v_y"))
        joints = [planar, lean, spin]
        coords, speeds = ["psi", "x", "y", "phi", "spin"], ["w_psi", "v_x", "v_y", "w_phi", "w_s"]
        constraints = (
            Constraint("v_x", lambda s: r * s["w_s"], "rolls along its heading"),
            Constraint("v_y", lambda s: 0 * s["w_s"], "no side slip"),
        )
    system = MultibodySystem(
        name="disc",
        description="a thin disc rolling on the ground",
        params=[Param(k, "") for k in VALUES],
        coordinates=[Signal(c, "") for c in coords],
        speeds=[Signal(s, "") for s in speeds],
        joints=joints,
        bodies=[disc],
        inputs=[],
        input_maps=[],
        constraints=constraints,
    )
    model = derive(system, P, ca.vertcat(*P.values()))
    names = [s.name for s in model.states]
    fns = {
        k: ca.Function(k, [model.x, model.p], [ca.densify(model.expressions[k])])
        for k in ("f", "energy")
    }
    p = list(VALUES.values())
    return names, lambda k, x: np.array(fns[k](x, p), dtype=float).ravel()


CONTACT = _system(inertial=False)
INERTIAL = _system(inertial=True)


def _by_name(names, values):
    return dict(zip(names, values, strict=True))


def test_both_descriptions_are_the_same_dynamics():
    (na, fa), (nb, fb) = CONTACT, INERTIAL
    assert sorted(na) == sorted(nb) == sorted(["psi", "x", "y", "phi", "w_psi", "w_phi", "w_s"])
    rng = np.random.default_rng(7)
    for _ in range(50):
        state = dict(zip(na, rng.uniform(-2, 2, len(na)), strict=True))
        state["phi"] = rng.uniform(-1.2, 1.2)
        xa, xb = [state[n] for n in na], [state[n] for n in nb]
        da, db = _by_name(na, fa("f", xa)), _by_name(nb, fb("f", xb))
        for n in na:
            assert abs(da[n] - db[n]) <= 1e-12 * (1 + abs(da[n])), (n, da[n], db[n])
        assert abs(fa("energy", xa)[0] - fb("energy", xb)[0]) <= 1e-12


def test_energy_is_conserved_while_rolling():
    names, f = INERTIAL
    x0 = dict(zip(names, [0.0] * len(names), strict=True))
    x0.update(phi=0.2, w_s=-8.0, w_phi=0.5, w_psi=0.3)
    x = [x0[n] for n in names]
    run = solve_ivp(lambda t, s: f("f", s), (0, 5), x, method="DOP853", rtol=1e-12, atol=1e-12)
    assert run.success
    e = [f("energy", s)[0] for s in run.y.T]
    assert max(abs(v - e[0]) for v in e) <= 1e-9 * abs(e[0])


def _upright_growth(speed):
    """Largest real part of the lean-steer modes of upright rolling at `speed` (central
    differences of f about the steady state; the rolling and heading directions are neutral)."""
    names, f = CONTACT
    base = dict(zip(names, [0.0] * len(names), strict=True))
    base["w_s"] = speed / VALUES["R"]
    x0 = np.array([base[n] for n in names])
    lateral = [names.index(n) for n in ("phi", "w_phi", "w_psi")]
    jac = np.zeros((3, 3))
    for k, j in enumerate(lateral):
        e = np.zeros(len(names))
        e[j] = 1e-6
        jac[:, k] = ((f("f", x0 + e) - f("f", x0 - e)) / 2e-6)[lateral]
    return max(np.linalg.eigvals(jac).real)


def test_upright_rolling_is_stable_above_the_classical_speed():
    critical = math.sqrt(VALUES["g"] * VALUES["R"] / 3)
    # Below: the disc falls (a real positive eigenvalue); above: the lean oscillates, neutrally
    # (the rolling disc conserves energy, so "stable" means purely imaginary eigenvalues).
    assert _upright_growth(0.9 * critical) > 1e-3
    assert abs(_upright_growth(1.1 * critical)) <= 1e-6
    assert abs(_upright_growth(3.0 * critical)) <= 1e-6
