"""The Whipple bicycle of the benchmark (Meijaard, Papadopoulos, Ruina & Schwab 2007), described
with general joints and rolling contacts: four rigid bodies — rear wheel R, rear frame with rider
B, front frame (fork and handlebar) H, front wheel F — a steer axis tilted by lambda, two thin
wheels rolling without slip. The rolling conditions are generated from the wheels' geometry
(`RollingContact`), not written by hand.

Frames (x forward, y left, z up; the paper's are x forward, y right, z down): A follows the rear
contact point, yawed by psi; L = A rolled by phi about a_x (phi > 0 leans right, as in the
paper); B = L pitched by theta about the rear axle, at r_R above the contact; H = B steered by
delta about the steer axis (sin lambda, 0, -cos lambda), pointing down as the paper's, through its
ground point (w + c, 0, -r_R) in B; the wheels spin about their frames' y axes. In the reference
configuration (upright, theta = delta = 0) the geometry is the paper's: wheelbase w, trail c.
The paper's inertia tensors are in its axes; in ours their x-z products change sign.
"""

from __future__ import annotations

import casadi as ca

from ..derived import Signal
from ..kinematics import Body, PlanarJoint, RevoluteJoint
from ..multibody import MultibodySystem, RollingContact, SteadyMotion, TorqueInput
from ..params import Param

_KINDS = {"m_": "mass", "r_": "length", "x_": "length", "z_": "length"}


def _param(name: str) -> Param:
    if name == "g":
        return Param("g", "m/s^2", "gravity")
    if name in ("w", "c"):
        return Param(name, "m", "length")
    if name == "lambda":
        return Param("lambda", "rad", "other")
    if name.startswith("I_"):
        return Param(name, "kg m^2", "other" if name.endswith("xz") else "inertia")
    return Param(name, "kg" if name.startswith("m_") else "m", _KINDS[name[:2]])


PARAM_NAMES = (
    *("w", "c", "lambda", "g"),
    *("r_R", "m_R", "I_Rxx", "I_Ryy"),
    *("x_B", "z_B", "m_B", "I_Bxx", "I_Byy", "I_Bzz", "I_Bxz"),
    *("x_H", "z_H", "m_H", "I_Hxx", "I_Hyy", "I_Hzz", "I_Hxz"),
    *("r_F", "m_F", "I_Fxx", "I_Fyy"),
)
PARAMS = [_param(n) for n in PARAM_NAMES]

COORDINATES = [
    Signal("psi", "rad", "yaw of the rear frame's heading"),
    Signal("x", "m", "rear contact point, inertial X"),
    Signal("y", "m", "rear contact point, inertial Y"),
    Signal("phi", "rad", "roll (lean), positive to the right"),
    Signal("theta", "rad", "rear frame pitch (fixed by the front wheel touching the ground)"),
    Signal("theta_R", "rad", "rear wheel angle (ignorable)"),
    Signal("delta", "rad", "steer angle, positive to the right"),
    Signal("theta_F", "rad", "front wheel angle (ignorable)"),
]
SPEEDS = [
    Signal("w_psi", "rad/s", "yaw rate"),
    Signal("v_x", "m/s", "rear contact point velocity, forward"),
    Signal("v_y", "m/s", "rear contact point velocity, left"),
    Signal("w_phi", "rad/s", "roll rate"),
    Signal("w_theta", "rad/s", "pitch rate"),
    Signal("w_R", "rad/s", "rear wheel spin relative to the rear frame"),
    Signal("w_delta", "rad/s", "steer rate"),
    Signal("w_F", "rad/s", "front wheel spin relative to the front frame"),
]
INPUTS = [
    Signal("T_phi", "N m", "roll torque on the rear frame (the paper's T_phi)"),
    Signal("T_delta", "N m", "steer torque between rear and front frame (the paper's T_delta)"),
]


def symbols():
    P = {n: ca.SX.sym(n) for n in PARAM_NAMES}
    return P, ca.vertcat(*[P[n] for n in PARAM_NAMES])


def whipple(P) -> MultibodySystem:
    lam = P["lambda"]
    steer_axis = (ca.sin(lam), 0, -ca.cos(lam))
    w, c, r_r, r_f = P["w"], P["c"], P["r_R"], P["r_F"]
    return MultibodySystem(
        name="whipple",
        description=(
            "The Whipple bicycle benchmark (Meijaard et al. 2007): rear wheel, rear frame with "
            "rider, front frame, front wheel; tilted steer axis; two wheels rolling without slip"
        ),
        params=PARAMS,
        coordinates=COORDINATES,
        speeds=SPEEDS,
        joints=[
            PlanarJoint("A", "N", coords=("psi", "x", "y"), speeds=("w_psi", "v_x", "v_y")),
            RevoluteJoint("L", "A", coord="phi", speed="w_phi", axis="x"),
            RevoluteJoint("B", "L", coord="theta", speed="w_theta", axis="y", at=(0, 0, r_r)),
            RevoluteJoint("RW", "B", coord="theta_R", speed="w_R", axis="y", axisymmetric=True),
            RevoluteJoint(
                "H", "B", coord="delta", speed="w_delta", axis=steer_axis, at=(w + c, 0, -r_r)
            ),
            RevoluteJoint(
                "FW",
                "H",
                coord="theta_F",
                speed="w_F",
                axis="y",
                at=(-c, 0, r_f),
                axisymmetric=True,
            ),
        ],
        bodies=[
            Body("rear_wheel", "RW", P["m_R"], inertia=(P["I_Rxx"], P["I_Ryy"], P["I_Rxx"])),
            Body(
                "rear_frame",
                "B",
                P["m_B"],
                centroid=(P["x_B"], 0, -P["z_B"] - r_r),
                inertia=(P["I_Bxx"], P["I_Byy"], P["I_Bzz"], 0, 0, -P["I_Bxz"]),
            ),
            Body(
                "front_frame",
                "H",
                P["m_H"],
                centroid=(P["x_H"] - w - c, 0, -P["z_H"]),
                inertia=(P["I_Hxx"], P["I_Hyy"], P["I_Hzz"], 0, 0, -P["I_Hxz"]),
            ),
            Body("front_wheel", "FW", P["m_F"], inertia=(P["I_Fxx"], P["I_Fyy"], P["I_Fxx"])),
        ],
        inputs=INPUTS,
        input_maps=[
            TorqueInput("T_phi", "L", "x"),
            TorqueInput("T_delta", "H", steer_axis, reaction="B"),
        ],
        contacts=(
            RollingContact("RW", r_r, touching_by_construction=True, description="rear wheel"),
            RollingContact("FW", r_f, description="front wheel"),
        ),
        contact_speeds=("v_x", "v_y", "w_psi", "w_theta", "w_F"),
        # Upright straight running: only the rear wheel turns, at v / r_R.
        steady_motion=SteadyMotion("w_R", 1 / r_r, ("phi", "delta", "w_phi", "w_delta")),
    )
