"""Joints about any axis and bodies with full inertia tensors (the steer axis of a bicycle is
tilted by its head angle; its rear frame has a product of inertia I_xz): the derivation against
closed forms, against the named-axis joints, and energy conservation of a tilted chain."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from twv_modeling.derived import Signal
from twv_modeling.kinematics import Body, RevoluteJoint
from twv_modeling.multibody import MultibodySystem, derive
from twv_modeling.params import Param

M_BAR, G = 2.0, 9.81


def _derive(joints, bodies, coords):
    P = {"m": ca.SX.sym("m"), "g": ca.SX.sym("g")}
    p_vec = ca.vertcat(P["m"], P["g"])
    system = MultibodySystem(
        name="chain",
        description="hinges about tilted axes on a fixed base",
        params=[Param("m", "kg", "mass"), Param("g", "m/s^2", "gravity")],
        coordinates=[Signal(c, "rad") for c in coords],
        speeds=[Signal(f"w_{c}", "rad/s") for c in coords],
        joints=joints(P),
        bodies=bodies(P),
        inputs=[],
        input_maps=[],
    )
    model = derive(system, P, p_vec)
    fns = {
        k: ca.Function(k, [model.x, model.p], [ca.densify(model.expressions[k])])
        for k in ("M", "Cp", "F", "f", "energy")
    }
    return lambda k, x: np.array(fns[k](x, [M_BAR, G]), dtype=float)


def _pendulum(axis, inertia, centroid):
    return _derive(
        lambda P: [RevoluteJoint("J", "N", coord="q", speed="w_q", axis=axis)],
        lambda P: [Body("bar", "J", P["m"], centroid=centroid, inertia=inertia)],
        ["q"],
    )


def _rodrigues(u, angle):
    k = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


AXIS = (math.sin(0.3), math.cos(0.3) * math.cos(0.4), math.cos(0.3) * math.sin(0.4))
CENTROID = (0.2, -0.1, 0.7)
TENSOR = (0.9, 0.7, 0.4, 0.05, -0.08, 0.12)  # Ixx, Iyy, Izz, Ixy, Iyz, Ixz


def test_a_tilted_hinge_has_the_closed_form_inertia_and_gravity_torque():
    model = _pendulum(AXIS, TENSOR, CENTROID)
    u, r = np.array(AXIS), np.array(CENTROID)
    ixx, iyy, izz, ixy, iyz, ixz = TENSOR
    tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    # Inertia about the axis line through the origin: u^T I u + m |u x r|^2.
    inertia = u @ tensor @ u + M_BAR * np.dot(np.cross(u, r), np.cross(u, r))
    for q in np.linspace(-3, 3, 13):
        x = [q, 0.7]
        assert abs(model("M", x)[0, 0] - inertia) <= 1e-14 * inertia
        # F = dV/dq with V = m g (R(q) r)_z, and no velocity terms about a fixed axis.
        dz = (-r * math.sin(q) + np.cross(u, r) * math.cos(q) + u * (u @ r) * math.sin(q))[2]
        assert abs(model("F", x)[0, 0] - M_BAR * G * dz) <= 1e-13
        assert abs(model("Cp", x)[0, 0]) <= 1e-14
        # Energy: T + V from the rotation matrix.
        v = M_BAR * G * (_rodrigues(u, q) @ r)[2]
        assert abs(model("energy", x)[0, 0] - (0.5 * inertia * 0.49 + v)) <= 1e-12


def test_a_unit_vector_axis_equals_the_named_axis():
    for name, vector in [("x", (1, 0, 0)), ("y", (0, 1, 0)), ("z", (0.0, 0.0, 1.0))]:
        named = _pendulum(name, (0.3, 0.5, 0.2), CENTROID)
        vec = _pendulum(vector, (0.3, 0.5, 0.2), CENTROID)
        for q in np.linspace(-3, 3, 7):
            for k in ("M", "F", "f", "energy"):
                assert np.allclose(named(k, [q, -1.3]), vec(k, [q, -1.3]), rtol=1e-14, atol=1e-14)


def test_a_tilted_chain_conserves_energy():
    # Two bodies, the second hinged on the first about another tilted axis, off its origin.
    axis2 = (0.6, 0.0, 0.8)
    model = _derive(
        lambda P: [
            RevoluteJoint("J1", "N", coord="a", speed="w_a", axis=AXIS),
            RevoluteJoint("J2", "J1", coord="b", speed="w_b", axis=axis2, at=(0.1, 0.3, -0.5)),
        ],
        lambda P: [
            Body("one", "J1", P["m"], centroid=CENTROID, inertia=TENSOR),
            Body("two", "J2", 0.5 * P["m"], centroid=(0.0, 0.2, -0.4), inertia=(0.1, 0.2, 0.15)),
        ],
        ["a", "b"],
    )
    x0 = [0.4, -1.0, 1.5, 2.0]
    run = solve_ivp(
        lambda t, x: model("f", x).ravel(), (0, 5), x0, method="DOP853", rtol=1e-12, atol=1e-12
    )
    assert run.success
    energies = [model("energy", x)[0, 0] for x in run.y.T]
    assert max(abs(e - energies[0]) for e in energies) <= 1e-8 * abs(energies[0])
    # M stays symmetric positive definite along the way.
    for x in run.y.T[::50]:
        m = model("M", x)
        assert np.allclose(m, m.T, rtol=0, atol=1e-14) and np.all(np.linalg.eigvalsh(m) > 0)


@pytest.mark.parametrize(
    ("axis", "inertia", "message"),
    [
        ((1.0, 1.0, 0.0), (0.3, 0.5, 0.2), "has length 1.41421, not 1"),
        ((1.0, 0.0), (0.3, 0.5, 0.2), "needs 3 components"),
        ("w", (0.3, 0.5, 0.2), "'w' is not x, y, z"),
        ("y", (0.3, 0.5, 0.2, 0.1), "3 principal moments or 6 tensor entries, not 4"),
    ],
)
def test_bad_axes_and_inertias_are_named(axis, inertia, message):
    with pytest.raises(ValueError, match=message):
        _pendulum(axis, inertia, CENTROID)
