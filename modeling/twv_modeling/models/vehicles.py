"""The vehicle models of docs/src/conventions.md, written as multibody data.

Frames: N inertial (z up); A = N yawed by theta (the planar joint, a_x forward, a_y left);
B = A pitched by phi about a_y (the pendulum). Coordinates (phi, x, y, theta), quasi-velocities
(w_y, v_x, v_y, w_z) with (v_x, v_y) the hinge velocity in A components.
"""

from __future__ import annotations

import casadi as ca

from ..derived import Signal
from ..kinematics import Body, PlanarJoint, RevoluteJoint
from ..multibody import Constraint, ForceInput, MultibodySystem, TorqueInput
from ..params import VEHICLE_PARAMS

COORDINATES = [
    Signal("phi", "rad", "pendulum pitch, positive leaning forward"),
    Signal("x", "m", "hinge position, inertial X"),
    Signal("y", "m", "hinge position, inertial Y"),
    Signal("theta", "rad", "yaw"),
]
SPEEDS = [
    Signal("w_y", "rad/s", "pitch rate"),
    Signal("v_x", "m/s", "forward velocity of the hinge"),
    Signal("v_y", "m/s", "lateral velocity of the hinge"),
    Signal("w_z", "rad/s", "yaw rate"),
]
FORCE_INPUTS = [
    Signal("F1", "N", "force pushing the base forward along a_x"),
    Signal("T2", "N m", "torque turning the base about +Z"),
]
NO_SIDE_SLIP = Constraint("v_y", lambda s: 0 * s["v_x"], "no side slip: v_y = 0")


def _planar(height=0):
    return PlanarJoint(
        "A", "N", coords=("theta", "x", "y"), speeds=("w_z", "v_x", "v_y"), height=height
    )


def _pendulum_joint():
    return RevoluteJoint("B", "A", coord="phi", speed="w_y", axis="y")


def _pendulum(P):
    return Body(
        "pendulum",
        "B",
        P["m2"],
        centroid=(0, 0, P["b"]),
        inertia=(P["I2_xx"], P["I2_yy"], P["I2_zz"]),
    )


def _study(P, name, description, constraints):
    base = Body(
        "base", "A", P["m1"], centroid=(0, 0, P["a"]), inertia=(P["I1_xx"], P["I1_yy"], P["I1_zz"])
    )
    return MultibodySystem(
        name=name,
        description=description,
        params=VEHICLE_PARAMS,
        coordinates=COORDINATES,
        speeds=SPEEDS,
        joints=[_planar(), _pendulum_joint()],
        bodies=[base, _pendulum(P)],
        inputs=FORCE_INPUTS,
        input_maps=[ForceInput("F1", "A", (1, 0, 0)), TorqueInput("T2", "A", "z")],
        constraints=constraints,
    )


def vehicle8(P):
    """The study's model: 4 coordinates and 4 pseudo speeds, the base free to slide sideways."""
    return _study(
        P,
        "vehicle8",
        "The study's vehicle: base (body + person) sliding and yawing in the plane, "
        "pendulum bar hinged on the axle; v_y free (no side-slip constraint).",
        (),
    )


def vehicle7(P):
    """The rolling vehicle: the same bodies with the no-side-slip constraint v_y = 0."""
    return _study(
        P,
        "vehicle7",
        "The study's vehicle with the nonholonomic no-side-slip constraint v_y = 0 "
        "(Hamel projection of the unconstrained Lagrangian).",
        (NO_SIDE_SLIP,),
    )


def segway7(P):
    """The physical Segway: two rolling wheels with spin inertia, chassis + rider as pendulum.

    The planar frame A sits on the axle midpoint (height R). Each wheel is a rotor about a_y at
    +-c/2 a_y (left at +c/2); rolling without slip fixes its spin rate relative to A:
    omega_L = (v_x - c/2 w_z)/R, omega_R = (v_x + c/2 w_z)/R, and no side slip gives v_y = 0.
    The motor torques act on the wheels about a_y and react on the pendulum.
    """
    R, half = P["R"], P["c"] / 2
    wheel_inertia = (P["J_d"], P["J_a"], P["J_d"])
    speeds = [
        *SPEEDS,
        Signal("omega_L", "rad/s", "left wheel spin rate relative to A"),
        Signal("omega_R", "rad/s", "right wheel spin rate relative to A"),
    ]
    coordinates = [
        *COORDINATES,
        Signal("psi_L", "rad", "left wheel angle"),
        Signal("psi_R", "rad", "right wheel angle"),
    ]
    return MultibodySystem(
        name="segway7",
        description="Segway: base = the two rolling wheels (spin inertia included), pendulum = "
        "chassis + rider; wheel torques (tau_L, tau_R) react on the pendulum.",
        params=VEHICLE_PARAMS,
        coordinates=coordinates,
        speeds=speeds,
        joints=[
            _planar(height=R),
            _pendulum_joint(),
            RevoluteJoint(
                "wheel_L", "A", "psi_L", "omega_L", axis="y", at=(0, half, 0), axisymmetric=True
            ),
            RevoluteJoint(
                "wheel_R", "A", "psi_R", "omega_R", axis="y", at=(0, -half, 0), axisymmetric=True
            ),
        ],
        bodies=[
            _pendulum(P),
            Body("wheel_L", "wheel_L", P["m_w"], inertia=wheel_inertia),
            Body("wheel_R", "wheel_R", P["m_w"], inertia=wheel_inertia),
        ],
        inputs=[
            Signal("tau_L", "N m", "left motor torque on the wheel about a_y"),
            Signal("tau_R", "N m", "right motor torque on the wheel about a_y"),
        ],
        input_maps=[
            TorqueInput("tau_L", "wheel_L", "y", reaction="B"),
            TorqueInput("tau_R", "wheel_R", "y", reaction="B"),
        ],
        constraints=(
            NO_SIDE_SLIP,
            Constraint(
                "omega_L",
                lambda s: (s["v_x"] - half * s["w_z"]) / R,
                "left wheel rolls without slip",
            ),
            Constraint(
                "omega_R",
                lambda s: (s["v_x"] + half * s["w_z"]) / R,
                "right wheel rolls without slip",
            ),
        ),
    )


BUILDERS = {"vehicle8": vehicle8, "vehicle7": vehicle7, "segway7": segway7}
PARAMS_SOURCE = {"vehicle8": "paper.toml", "vehicle7": "paper.toml", "segway7": "segway.toml"}


def symbols():
    """One symbol per vehicle parameter, and their vector in declaration order."""
    P = {p.name: ca.SX.sym(p.name) for p in VEHICLE_PARAMS}
    return P, ca.vertcat(*[P[p.name] for p in VEHICLE_PARAMS])
