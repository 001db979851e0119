"""Frames and joints: the kinematic building blocks of a multibody description (like ProPac).

Every joint connects a parent frame to a child frame. It owns some generalized coordinates and
as many quasi-velocities, and gives, in closed form:
- the relative rotation R (child components -> parent components) and translation t (the child
  origin in parent components),
- the kinematic block q_dot = V(q) p of its own coordinates,
- its relative twist in child components (angular velocity, velocity of the child origin),
- the structure coefficients of its quasi-velocities: [X_j, X_k] = sum_l gamma[l][j][k] X_l for
  the vector fields X_j = V[:, j]. They are constants of the joint's Lie algebra (se(2), so(2)),
  which keeps the Hamel/Euler-Poincare terms free of unsimplified sin^2 + cos^2.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

ZERO3 = (0, 0, 0)


def vec3(v) -> ca.SX:
    return ca.vertcat(*[ca.SX(e) if isinstance(e, int | float) else e for e in v])


def rot_z(angle: ca.SX) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.blockcat([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rot_y(angle: ca.SX) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.blockcat([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_x(angle: ca.SX) -> ca.SX:
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.blockcat([[1, 0, 0], [0, c, -s], [0, s, c]])


ROTATIONS = {"x": rot_x, "y": rot_y, "z": rot_z}
AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1)}


def axis_vector(axis, what: str) -> ca.SX:
    """A joint or torque axis in its frame: "x", "y", "z", or a unit vector of three numbers or
    parameter expressions (e.g. a steer axis tilted by a head angle lam: (sin(lam), 0, cos(lam))).
    A numeric vector must have unit length; a symbolic one is the describer's promise."""
    if isinstance(axis, str):
        if axis not in AXES:
            raise ValueError(f"{what}: axis {axis!r} is not x, y, z or a unit vector")
        return vec3(AXES[axis])
    if len(axis) != 3:
        raise ValueError(f"{what}: an axis needs 3 components, not {len(axis)}")
    if all(isinstance(e, int | float) for e in axis):
        norm2 = sum(float(e) ** 2 for e in axis)
        if abs(norm2 - 1.0) > 1e-12:
            raise ValueError(f"{what}: axis {tuple(axis)} has length {norm2**0.5:.6g}, not 1")
    return vec3(axis)


def rot_about(u: ca.SX, angle: ca.SX) -> ca.SX:
    """Rotation by `angle` about the unit axis u: Rodrigues, I + sin K + (1 - cos) K^2, K = [u]x."""
    k = ca.skew(u)
    return ca.SX.eye(3) + ca.sin(angle) * k + (1 - ca.cos(angle)) * (k @ k)


def inertia_matrix(inertia, what: str) -> ca.SX:
    """A body's inertia tensor about its centroid in its frame: the principal moments
    (Ixx, Iyy, Izz), or all six entries (Ixx, Iyy, Izz, Ixy, Iyz, Ixz) of the (symmetric) tensor
    (the bicycle benchmark's I_Bxz is its x-z entry)."""
    if len(inertia) == 3:
        return ca.diag(vec3(inertia))
    if len(inertia) == 6:
        ixx, iyy, izz, ixy, iyz, ixz = (
            ca.SX(e) if isinstance(e, int | float) else e for e in inertia
        )
        return ca.blockcat([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    raise ValueError(
        f"{what}: inertia needs 3 principal moments or 6 tensor entries, not {len(inertia)}"
    )


@dataclass
class PlanarJoint:
    """SE(2): the child translates in the parent's x-y plane at a fixed height and yaws about z.

    Coordinates (theta, x, y); quasi-velocities (w_z, v_x, v_y): the yaw rate and the velocity of
    the child origin in child components, so that
    theta_dot = w_z, x_dot = v_x cos(theta) - v_y sin(theta),
    y_dot = v_x sin(theta) + v_y cos(theta).
    """

    name: str
    parent: str
    coords: tuple[str, str, str] = ("theta", "x", "y")
    speeds: tuple[str, str, str] = ("w_z", "v_x", "v_y")
    height: object = 0

    def rotation(self, q):
        return rot_z(q[0])

    def translation(self, q):
        return vec3((q[1], q[2], self.height))

    def velocity_map(self, q):
        c, s = ca.cos(q[0]), ca.sin(q[0])
        return ca.blockcat([[1, 0, 0], [0, c, -s], [0, s, c]])

    def twist(self, p):
        return vec3((0, 0, p[0])), vec3((p[1], p[2], 0))

    def structure(self):
        # [X_wz, X_vx] = X_vy and [X_wz, X_vy] = -X_vx; X_vx and X_vy commute.
        gamma = _zeros3(3)
        gamma[2][0][1], gamma[2][1][0] = 1, -1
        gamma[1][0][2], gamma[1][2][0] = -1, 1
        return gamma


@dataclass
class _OneAxisJoint:
    """What a hinge and a slider share: one coordinate along or about one axis through `at`."""

    name: str
    parent: str
    coord: str
    speed: str
    axis: str | tuple = "x"
    at: tuple = ZERO3

    @property
    def coords(self):
        return (self.coord,)

    @property
    def speeds(self):
        return (self.speed,)

    def velocity_map(self, q):
        return ca.SX.eye(1)

    def structure(self):
        return _zeros3(1)


@dataclass
class RevoluteJoint(_OneAxisJoint):
    """A hinge about a fixed axis through a point of the parent frame: "x", "y", "z" or any unit
    vector in the parent frame (see `axis_vector`), through `at`.

    One coordinate (the angle) and one quasi-velocity (its rate). `axisymmetric` marks a rotor
    (a wheel): the child's inertia is symmetric about the axis and its centroid lies on it, so the
    kinetic energy does not depend on the angle, which is then an ignorable coordinate. The child
    frame of such a joint is the non-spinning carrier; the spin only adds to the angular velocity.
    """

    axis: str | tuple = "y"
    axisymmetric: bool = False

    def rotation(self, q):
        if self.axisymmetric:
            return ca.SX.eye(3)
        if isinstance(self.axis, str) and self.axis in ROTATIONS:
            return ROTATIONS[self.axis](q[0])
        return rot_about(axis_vector(self.axis, f"joint {self.name}"), q[0])

    def translation(self, q):
        return vec3(self.at)

    def twist(self, p):
        return axis_vector(self.axis, f"joint {self.name}") * p[0], vec3(ZERO3)


@dataclass
class PrismaticJoint(_OneAxisJoint):
    """A slider: the child translates along a fixed unit axis of the parent frame (see
    `axis_vector`), starting from `at`, without rotating. One coordinate (the displacement) and
    its rate. Two of them and a hinge about z describe planar motion in inertial velocity
    components, where rolling constraints have coordinate-dependent coefficients."""

    def rotation(self, q):
        return ca.SX.eye(3)

    def translation(self, q):
        return vec3(self.at) + axis_vector(self.axis, f"joint {self.name}") * q[0]

    def twist(self, p):
        return vec3(ZERO3), axis_vector(self.axis, f"joint {self.name}") * p[0]


@dataclass
class Body:
    """A rigid body fixed in a joint's child frame.

    `centroid` is the centre of mass in that frame; `inertia` about the centroid along the frame
    axes: the principal moments (Ixx, Iyy, Izz) or the six tensor entries (Ixx, Iyy, Izz, Ixy, Iyz,
    Ixz), see `inertia_matrix`.
    """

    name: str
    frame: str
    mass: object
    centroid: tuple = ZERO3
    inertia: tuple = ZERO3
    description: str = ""
    extra: dict = field(default_factory=dict)


def _zeros3(n: int):
    return [[[0 for _ in range(n)] for _ in range(n)] for _ in range(n)]
