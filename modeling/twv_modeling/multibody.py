"""Multibody systems described as data, and their Euler-Poincare (Hamel) equations.

Like ProPac: joints, bodies, the tree they form, gravity, velocity constraints and input maps go
in; out come V(q), M(q), C(q,p)p, F(q), Q(u) and the state equations

    q_dot = V(q) p,    M(q) p_dot + C(q,p) p + F(q) = Q(u).

The equations are Hamel's equations in the quasi-velocities p of the *unconstrained* system,

    d/dt dL/dp_k - X_k(L) - sum_{j,l} gamma^l_{jk} p_j dL/dp_l = Q_k,

with X_k = V[:, k] and [X_j, X_k] = sum_l gamma^l_{jk} X_l. Nonholonomic constraints are imposed
the Kwatny/ProPac way: the quasi-velocities are changed so that each constraint reads
"a constraint speed is zero", the equations are written for the admissible speeds only, and the
constraint speeds are set to zero *after* differentiating. Substituting the constraint into the
Lagrangian first would drop the gyroscopic terms gamma * dL/dp_c that do no work.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from .canonical import canonical
from .derived import DerivedModel, Signal, operations
from .kinematics import (
    Body,
    PlanarJoint,
    PrismaticJoint,
    RevoluteJoint,
    axis_vector,
    inertia_matrix,
    vec3,
)
from .linsolve import solve_spd
from .params import Param

GROUND = "N"


@dataclass
class Constraint:
    """A velocity constraint solved for one quasi-velocity.

    `expression(symbols)` gives the dependent speed as a linear combination of the independent
    ones; `symbols` maps the independent speed names and the coordinate names to their symbols.
    The coefficients may depend on parameters and on coordinates (a rolling wheel described in
    inertial velocity components: x_dot = R w_s cos(psi)); then the structure functions of the
    new quasi-velocities get the derivative terms of the change of speeds.
    """

    dependent: str
    expression: Callable[[dict], ca.SX]
    description: str = ""


@dataclass
class RollingContact:
    """A thin wheel rolling without slip on the ground plane (N's z = 0).

    `wheel` is the wheel's rotor joint (`RevoluteJoint(..., axisymmetric=True)`): its frame's
    origin is the wheel centre, its axis the axle, and the wheel's angular velocity includes the
    spin. The contact point is P = C - R d with d the unit vector in the wheel plane closest to
    the ground normal n, d = (n - (n.a) a)/|n - (n.a) a|; the wheel's material point there does
    not move: v_C - R omega x d = 0. The two horizontal components are the no-slip conditions;
    the vertical one is the rate of the contact condition (the wheel touching the ground), left
    out when the description keeps the wheel on the ground by construction (a wheel whose centre
    is placed at R above a frame that moves with the contact point). The conditions are solved
    for the system's `contact_speeds`; a coordinate they constrain holonomically stays in the
    state (its drift from the contact condition is the integrator's to keep small).
    """

    wheel: str
    radius: object
    touching_by_construction: bool = False
    description: str = ""


@dataclass
class SteadyMotion:
    """Straight running at speed v, an equilibrium of the state's non-drifting part: every
    state zero except `speed_state` = v * `per_unit_speed` (a parameter expression, e.g.
    1 / r_R for a rear wheel's spin). `modes` are the states whose linearisation about it is
    studied against speed (`twv linear --speed`): the bicycle's lean and steer."""

    speed_state: str
    per_unit_speed: object
    modes: tuple[str, ...]


@dataclass
class ForceInput:
    """Input force along `direction` (frame components) at the origin of `frame`."""

    input: str
    frame: str
    direction: tuple


@dataclass
class TorqueInput:
    """Input torque about `axis` (frame components) on `frame`, its reaction on `reaction`."""

    input: str
    frame: str
    axis: str | tuple
    reaction: str | None = None


@dataclass
class MultibodySystem:
    name: str
    description: str
    params: list[Param]
    coordinates: list[Signal]
    speeds: list[Signal]
    joints: list[PlanarJoint | RevoluteJoint | PrismaticJoint]
    bodies: list[Body]
    inputs: list[Signal]
    input_maps: list[ForceInput | TorqueInput]
    gravity: str = "g"
    constraints: tuple[Constraint, ...] = ()
    contacts: tuple[RollingContact, ...] = ()
    contact_speeds: tuple[str, ...] = ()
    steady_motion: SteadyMotion | None = None


class ModelError(ValueError):
    """A multibody description that cannot be derived (the message says why)."""


@dataclass
class _Frame:
    """Kinematics of one frame F, in the components of its reference frame G.

    G is the child frame of the nearest planar joint at or above F (or N): velocities are
    native there, so expressions stay free of unsimplified sin^2 + cos^2 from rotating back and
    forth. `rot` is R_GF (F components -> G components)."""

    ref: str
    omega: ca.SX  # angular velocity of F, G components
    velocity: ca.SX  # velocity of F's origin, G components
    rot: ca.SX  # R_GF


class _Kinematics:
    """Frame twists and poses of a system for given coordinate and speed symbols."""

    def __init__(self, system: MultibodySystem, q: dict, p: dict):
        self.joints = {j.name: j for j in system.joints}
        zero = vec3((0, 0, 0))
        self.frames = {GROUND: _Frame(GROUND, zero, zero, ca.SX.eye(3))}
        self.relative = {}
        self.translation = {}
        for joint in self._ordered(system.joints):
            parent = self.frames[joint.parent]
            qj = [q[c] for c in joint.coords]
            pj = [p[s] for s in joint.speeds]
            R, t = joint.rotation(qj), joint.translation(qj)
            w_rel, v_rel = joint.twist(pj)
            self.relative[joint.name], self.translation[joint.name] = R, t
            t_ref = parent.rot @ t
            if isinstance(joint, PlanarJoint):
                # New reference frame: express the parent's twist in the child's components.
                to_child = R.T @ parent.rot.T
                self.frames[joint.name] = _Frame(
                    ref=joint.name,
                    omega=to_child @ parent.omega + w_rel,
                    velocity=to_child @ (parent.velocity + ca.cross(parent.omega, t_ref)) + v_rel,
                    rot=ca.SX.eye(3),
                )
            else:
                rot = parent.rot @ R
                self.frames[joint.name] = _Frame(
                    ref=parent.ref,
                    omega=parent.omega + rot @ w_rel,
                    velocity=parent.velocity + ca.cross(parent.omega, t_ref) + rot @ v_rel,
                    rot=rot,
                )

    def _ordered(self, joints):
        done, ordered, pending = {GROUND}, [], list(joints)
        while pending:
            ready = [j for j in pending if j.parent in done]
            if not ready:
                names = ", ".join(j.name for j in pending)
                raise ModelError(f"joints {names} are not connected to the ground frame {GROUND}")
            for j in ready:
                parent = self.joints.get(j.parent)
                if isinstance(parent, RevoluteJoint) and parent.axisymmetric:
                    raise ModelError(
                        f"joint {j.name}: a rotor frame ({j.parent}) carries bodies only"
                    )
                ordered.append(j)
                done.add(j.name)
                pending.remove(j)
        return ordered

    def _path(self, frame: str) -> list[str]:
        path = []
        while frame != GROUND:
            path.append(frame)
            frame = self.joints[frame].parent
        return list(reversed(path))

    def rotation_between(self, target: str, source: str) -> ca.SX:
        """R such that (source components) -> (target components), composed along the tree so
        that rotations above the common ancestor (the yaw) cancel exactly."""
        a, b = self._path(target), self._path(source)
        n = 0
        while n < min(len(a), len(b)) and a[n] == b[n]:
            n += 1
        r_a, r_b = ca.SX.eye(3), ca.SX.eye(3)
        for f in a[n:]:
            r_a = r_a @ self.relative[f]
        for f in b[n:]:
            r_b = r_b @ self.relative[f]
        return r_a.T @ r_b

    def ground_rotation(self, ref: str) -> ca.SX:
        """R_NG of a reference frame G (`_Frame.ref`): its components -> N components."""
        return self.position(ref)[1] if ref != GROUND else ca.SX.eye(3)

    def up_in(self, ref: str) -> ca.SX:
        """The ground's upward normal in the components of reference frame `ref`."""
        return self.ground_rotation(ref).T @ vec3((0, 0, 1))

    def position(self, frame: str) -> tuple[ca.SX, ca.SX]:
        """Origin position in N and R_NF, composed from the root."""
        origin, rot = vec3((0, 0, 0)), ca.SX.eye(3)
        for f in self._path(frame):
            origin = origin + rot @ self.translation[f]
            rot = rot @ self.relative[f]
        return origin, rot


@dataclass
class _BodyKinematics:
    mass: ca.SX
    inertia: ca.SX
    v: ca.SX  # centroid velocity, reference components
    omega: ca.SX  # angular velocity, body components
    height: ca.SX  # centroid height in N
    lin: ca.SX  # linear momentum, N components
    ang: ca.SX  # angular momentum about the N origin, z component


def _body_kinematics(kin: _Kinematics, body: Body) -> _BodyKinematics:
    fr = kin.frames[body.frame]
    c = vec3(body.centroid)
    inertia = inertia_matrix(body.inertia, f"body {body.name}")
    v_c = fr.velocity + ca.cross(fr.omega, fr.rot @ c)
    omega_body = fr.rot.T @ fr.omega
    origin, rot_nf = kin.position(body.frame)
    rot_ng = kin.ground_rotation(fr.ref)
    r_c = origin + rot_nf @ c
    lin = body.mass * (rot_ng @ v_c)
    ang = ca.cross(r_c, lin)[2] + (rot_nf @ (inertia @ omega_body))[2]
    return _BodyKinematics(body.mass, inertia, v_c, omega_body, r_c[2], lin, ang)


def _input_power(kin: _Kinematics, m, u: dict) -> ca.SX:
    fr = kin.frames[m.frame]
    if isinstance(m, ForceInput):
        return u[m.input] * ca.dot(fr.rot @ vec3(m.direction), fr.velocity)
    axis = fr.rot @ axis_vector(m.axis, f"torque input {m.input}")
    omega = fr.omega
    if m.reaction is not None:
        other = kin.frames[m.reaction]
        to_ref = kin.rotation_between(fr.ref, other.ref) if other.ref != fr.ref else ca.SX.eye(3)
        omega = omega - to_ref @ other.omega
    return u[m.input] * ca.dot(axis, omega)


def _check_rotor_bodies(system: MultibodySystem):
    joints = {j.name: j for j in system.joints}
    for body in system.bodies:
        j = joints.get(body.frame)
        if isinstance(j, RevoluteJoint) and j.axisymmetric:
            if not (isinstance(j.axis, str) and j.axis in "xyz") or len(body.inertia) != 3:
                raise ModelError(
                    f"body {body.name} on rotor {j.name}: a rotor spins about x, y or z of its "
                    "frame and has principal inertias"
                )
            axis = "xyz".index(j.axis)
            transverse = [body.inertia[i] for i in range(3) if i != axis]
            # Structural equality to a depth that covers formulas written twice (m R^2 / 4).
            same = ca.is_equal(ca.SX(transverse[0]), ca.SX(transverse[1]), 16)
            if any(ca.SX(e).is_zero() is False for e in body.centroid) or not same:
                raise ModelError(
                    f"body {body.name} on rotor {j.name}: needs its centroid on the axis and equal "
                    "transverse inertias"
                )


def derive(system: MultibodySystem, param_symbols: dict, p_vec: ca.SX) -> DerivedModel:
    """Derive the Poincare equations of `system` and return the model for export."""
    coord_names = [c.name for c in system.coordinates]
    speed_names = [s.name for s in system.speeds]
    n = len(coord_names)
    if len(speed_names) != n:
        raise ModelError("as many quasi-velocities as coordinates are needed")
    _check_rotor_bodies(system)
    joint_coords = [c for j in system.joints for c in j.coords]
    if sorted(joint_coords) != sorted(coord_names):
        raise ModelError("every coordinate must belong to exactly one joint")

    q = {c: ca.SX.sym(c) for c in coord_names}
    pf = {s: ca.SX.sym(s) for s in speed_names}
    u = {i.name: ca.SX.sym(i.name) for i in system.inputs}
    q_vec = ca.vertcat(*[q[c] for c in coord_names])
    u_vec = ca.vertcat(*[u[i.name] for i in system.inputs])
    g = param_symbols[system.gravity]

    # V(q) and the structure coefficients of the full quasi-velocities, joint by joint.
    V_full = ca.SX(n, n)
    gamma = [[[0 for _ in range(n)] for _ in range(n)] for _ in range(n)]
    for j in system.joints:
        ci = [coord_names.index(c) for c in j.coords]
        si = [speed_names.index(s) for s in j.speeds]
        Vj = j.velocity_map([q[c] for c in j.coords])
        gj = j.structure()
        for a, ia in enumerate(ci):
            for b, ib in enumerate(si):
                V_full[ia, ib] = Vj[a, b]
        for lo, il in enumerate(si):
            for jo, ij in enumerate(si):
                for ko, ik in enumerate(si):
                    gamma[il][ij][ik] = gj[lo][jo][ko]

    kin = _Kinematics(system, q, pf)
    bodies = [_body_kinematics(kin, b) for b in system.bodies]
    U = sum(b.mass * g * b.height for b in bodies)
    lin = sum((b.lin for b in bodies), vec3((0, 0, 0)))
    ang = sum(b.ang for b in bodies)
    power = sum(_input_power(kin, m, u) for m in system.input_maps)

    constraints = list(system.constraints) + _contact_constraints(
        system, kin, q, pf, [c.dependent for c in system.constraints]
    )

    # Change of quasi-velocities: independent speeds plus one constraint speed per constraint.
    dependent = [c.dependent for c in constraints]
    independent = [s for s in speed_names if s not in dependent]
    cspeed = {d: ca.SX.sym(f"c_{d}") for d in dependent}
    full_of_new = dict(pf)
    ind_syms = {**q, **{s: pf[s] for s in independent}}
    for con in constraints:
        full_of_new[con.dependent] = con.expression(ind_syms) + cspeed[con.dependent]
    new_speeds = [pf[s] for s in independent] + [cspeed[d] for d in dependent]
    p_new = ca.vertcat(*new_speeds)
    pf_vec = ca.vertcat(*[pf[s] for s in speed_names])
    pf_expr = ca.vertcat(*[full_of_new[s] for s in speed_names])
    Tmat = ca.jacobian(pf_expr, p_new)
    if ca.depends_on(Tmat, p_new):
        raise ModelError("constraints must be linear in the speeds")
    m = len(independent)
    c_vec = ca.vertcat(*[cspeed[d] for d in dependent]) if dependent else ca.SX(0, 1)

    def on_constraint(e):
        return ca.substitute(e, c_vec, ca.SX.zeros(c_vec.numel())) if dependent else e

    if ca.depends_on(Tmat, q_vec):
        # Coefficients that depend on the configuration (rolling contacts): Kane's equations in
        # the independent speeds, p = T_I(q) p_ind. The same equations as the unconstrained
        # Hamel equations projected onto the admissible speeds (d'Alembert), written body by
        # body from the constrained velocities, so that nothing of the unconstrained n x n
        # system is formed: the Whipple bicycle's f in 2,489 operations instead of 5,093
        # (test_whipple_kane.py checks it against sympy's Kane method, test_rolling_disc.py
        # against the change of quasi-velocities below).
        pf_on = on_constraint(pf_expr)
        p_ind = ca.vertcat(*[pf[s] for s in independent])
        T_I = ca.jacobian(pf_on, p_ind)

        def on(e):
            return ca.substitute(e, pf_vec, pf_on)

        qdot = on(V_full @ pf_vec)
        M_c, Cp_c, F_c = _kane(system, kin, bodies, on, p_ind, (q_vec, qdot), g)
        Q_c = T_I.T @ on(ca.gradient(power, pf_vec))
        energy_c = on(_kinetic_energy((b, b.v, b.omega) for b in bodies)) + U
        momentum_c = on(ca.vertcat(lin[0], lin[1], ang))
    else:
        # Coordinate-free coefficients: Hamel's equations in the new quasi-velocities (the
        # constraint speeds among them), projected, and only then the constraint speeds set to 0.
        Tinv = _inverse_of_speed_change(speed_names, independent, constraints, ind_syms, pf)
        gamma_new = _transform_structure(gamma, Tmat, Tinv, n)

        def to_new(e):
            return ca.substitute(e, pf_vec, pf_expr)

        V_new = V_full @ Tmat
        M_full, Cp_full, T_new, qdot_new = _hamel(bodies, to_new, p_new, q_vec, V_new, gamma_new)
        qdot = on_constraint(qdot_new)
        M_c = on_constraint(M_full[:m, :m])
        Cp_c = on_constraint(Cp_full[:m])
        F_c = on_constraint((V_new.T @ ca.gradient(U, q_vec))[:m])
        Q_c = on_constraint(ca.gradient(to_new(power), p_new)[:m])
        energy_c = on_constraint(T_new + U)
        lin_new, ang_new = to_new(lin), to_new(ang)
        momentum_c = on_constraint(ca.vertcat(lin_new[0], lin_new[1], ang_new))

    # Merging common subexpressions also cancels exact repeats (a - a = 0), so entries that
    # vanish identically, such as the left/right wheel cross terms, become structural zeros.
    # Then each entry in the form a careful person writes (canonical.py: sin² + cos² = 1,
    # cancelling pairs gone, parameter coefficients factored), where that has no more operations.
    names = [p_vec[i].name() for i in range(p_vec.numel())]
    params = set(names)
    env = {e.name(): e for e in [*q.values(), *pf.values(), *u.values(), *cspeed.values()]}
    env.update({n: p_vec[i] for i, n in enumerate(names)})
    M = canonical(ca.cse(M_c), params, env)
    Cp = canonical(ca.cse(Cp_c), params, env)
    F = canonical(ca.cse(F_c), params, env)
    Q = canonical(ca.cse(Q_c), params, env)
    energy = ca.cse(energy_c)
    momentum = ca.cse(momentum_c)

    # Ignorable coordinates (rotor angles) leave the state; check that nothing depends on them.
    rotor_coords = [
        j.coord for j in system.joints if isinstance(j, RevoluteJoint) and j.axisymmetric
    ]
    state_coords = [c for c in coord_names if c not in rotor_coords]
    rotor_vec = ca.vertcat(*[q[c] for c in rotor_coords]) if rotor_coords else ca.SX(0, 1)
    for name, e in (("M", M), ("Cp", Cp), ("F", F), ("Q", Q), ("energy", energy)):
        if rotor_coords and ca.depends_on(e, rotor_vec):
            raise ModelError(f"{name} depends on the rotor angle; the rotor is not axisymmetric")

    p_ind = p_new[:m]
    rows = [coord_names.index(c) for c in state_coords]
    qdot_state = ca.vertcat(*[qdot[r] for r in rows])
    rhs = canonical(ca.cse(Q - Cp - F), params, env)
    pdot = solve_spd(M, rhs)
    x = ca.vertcat(*[q[c] for c in state_coords], p_ind)
    f = ca.vertcat(qdot_state, pdot)

    states = [c for c in system.coordinates if c.name in state_coords] + [
        s for s in system.speeds if s.name in independent
    ]
    expressions = {
        "f": f,
        "M": M,
        "Cp": Cp,
        "F": F,
        "Q": Q,
        "energy": energy,
        "momentum": momentum,
    }
    header_extra = {}
    if system.steady_motion is not None:
        expressions["steady"], header_extra = _steady(system.steady_motion, states)
    return DerivedModel(
        name=system.name,
        kind="multibody",
        description=system.description,
        states=states,
        inputs=list(system.inputs),
        params=list(system.params),
        x=x,
        u=u_vec,
        p=p_vec,
        expressions=expressions,
        jac_x=_jacobian_x(f, x, [x, u_vec, p_vec], M, rhs, len(state_coords)),
        header={
            "coordinates": state_coords,
            "ignorable_coordinates": rotor_coords,
            "speeds": independent,
            "constraints": [
                {"dependent": c.dependent, "description": c.description} for c in constraints
            ],
            "mass_matrix_solve": "symbolic LDL^T in f (structural zeros kept)",
            **header_extra,
        },
    )


def _steady(steady: SteadyMotion, states):
    """The state at unit speed (function `steady` of the IR) and the header entry naming it."""
    names = [s.name for s in states]
    unknown = [n for n in (steady.speed_state, *steady.modes) if n not in names]
    if unknown:
        raise ModelError(f"steady motion: {', '.join(unknown)} not states ({', '.join(names)})")
    unit = [ca.SX(0)] * len(names)
    unit[names.index(steady.speed_state)] = ca.SX(steady.per_unit_speed)
    expr = ca.vertcat(*unit)  # a function of the parameters only
    header = {"steady_motion": {"speed_state": steady.speed_state, "modes": list(steady.modes)}}
    return expr, header


def _hamel(bodies, speed_of, p_vec, q_vec, V, gamma):
    """Hamel's equations' M, Cp = C(q, p) p and the kinetic energy T in the quasi-velocities
    `p_vec` (q_dot = V p, structure coefficients `gamma`), the body velocities written in them by
    `speed_of`; also q_dot. v and omega are linear in p: M = sum m Jv^T Jv + Jw^T I Jw,
    P = dT/dp = M p, dT/dq = sum m (dv/dq)^T v + (dw/dq)^T I w, by the chain rule body by body."""
    n = p_vec.numel()
    M, P, dT_dq, moving = ca.SX(n, n), ca.SX(n, 1), ca.SX(n, 1), []
    for b in bodies:
        v, w = speed_of(b.v), speed_of(b.omega)
        moving.append((b, v, w))
        Iw = b.inertia @ w
        Jv, Jw = ca.jacobian(v, p_vec), ca.jacobian(w, p_vec)
        M = M + b.mass * (Jv.T @ Jv) + Jw.T @ (b.inertia @ Jw)
        P = P + b.mass * (Jv.T @ v) + Jw.T @ Iw
        dT_dq = dT_dq + b.mass * (ca.jacobian(v, q_vec).T @ v) + ca.jacobian(w, q_vec).T @ Iw
    T = _kinetic_energy(moving)
    qdot = V @ p_vec
    Cp = ca.jacobian(P, q_vec) @ qdot - V.T @ dT_dq
    for k in range(n):
        term = 0
        for b in range(n):
            for j in range(n):
                if not _zero(gamma[b][j][k]):
                    term = term + gamma[b][j][k] * p_vec[j] * P[b]
        Cp[k] = Cp[k] - term
    return M, Cp, T, qdot


def _kinetic_energy(moving) -> ca.SX:
    """T = sum of m v.v / 2 + w.I w / 2 over (body, v, w): each body with its velocities."""
    T = 0
    for b, v, w in moving:
        T = T + 0.5 * b.mass * ca.dot(v, v) + 0.5 * ca.dot(w, b.inertia @ w)
    return T


def _kane(system, kin, bodies, on, p_ind, q_qdot, g):
    """Kane's equations M p_ind_dot + Cp + F = Q in the independent speeds `p_ind`, the body
    velocities written on the constraints by `on`: the partial velocities Jv = dv/dp_ind,
    Jw = dw/dp_ind give M = sum m Jv^T Jv + Jw^T I Jw; the rest of the accelerations, by forward
    differentiation along q_dot (a directional derivative, far smaller than the Jacobian times
    q_dot), gives Cp; gravity is F = sum m g Jv^T up.

    Velocities are in the components of a frame G that turns with w_G (the reference frame of
    `_Frame`), so a = d/dt v + w_G x v. Angular velocities are in the body's components, whose
    frame turns with the body (d/dt w is the angular acceleration) except on a rotor, whose frame
    is the non-spinning carrier: there the inertia is constant in the carrier, and the rate of
    the angular momentum is I d/dt w + w_carrier x I w."""
    q_vec, qdot = q_qdot
    m = p_ind.numel()
    M, Cp, F = ca.SX(m, m), ca.SX(m, 1), ca.SX(m, 1)
    for body, b in zip(system.bodies, bodies, strict=True):
        frame, joint = kin.frames[body.frame], kin.joints.get(body.frame)  # None: the ground
        v, w = on(b.v), on(b.omega)
        rotor = isinstance(joint, RevoluteJoint) and joint.axisymmetric
        w_frame = on(frame.rot.T @ kin.frames[joint.parent].omega) if rotor else w
        w_ref = on(kin.frames[frame.ref].omega)
        up = kin.up_in(frame.ref)
        Jv, Jw = ca.jacobian(v, p_ind), ca.jacobian(w, p_ind)
        a = ca.jtimes(v, q_vec, qdot) + ca.cross(w_ref, v)
        alpha = ca.jtimes(w, q_vec, qdot)
        M = M + b.mass * (Jv.T @ Jv) + Jw.T @ (b.inertia @ Jw)
        momentum_rate = b.inertia @ alpha + ca.cross(w_frame, b.inertia @ w)
        Cp = Cp + b.mass * (Jv.T @ a) + Jw.T @ momentum_rate
        F = F + b.mass * g * (Jv.T @ up)
    return M, Cp, F


def _contact_constraints(system, kin, q, pf, already_dependent) -> list[Constraint]:
    """The rolling contacts' conditions solved for `contact_speeds` (with the explicit
    constraints' dependent speeds substituted first), as constraints on the independent speeds."""
    if not system.contacts:
        if system.contact_speeds:
            raise ModelError("contact_speeds given without contacts")
        return []
    joints = {j.name: j for j in system.joints}
    rows = []
    for contact in system.contacts:
        j = joints.get(contact.wheel)
        if not (isinstance(j, RevoluteJoint) and j.axisymmetric):
            raise ModelError(f"contact on {contact.wheel}: the wheel must be a rotor joint")
        frame = kin.frames[contact.wheel]
        normal = kin.up_in(frame.ref)  # the ground normal in the reference components
        axle = frame.rot @ axis_vector(j.axis, f"wheel {j.name}")
        down = normal - ca.dot(normal, axle) * axle
        d = down / ca.norm_2(down)
        v_p = frame.velocity - contact.radius * ca.cross(frame.omega, d)
        # Two horizontal directions (the reference frame's x and y when it is yawed only).
        e1 = ca.cross(vec3((0, 1, 0)), normal)
        e2 = ca.cross(normal, e1)
        rows += [ca.dot(v_p, e1), ca.dot(v_p, e2)]
        if not contact.touching_by_construction:
            rows.append(ca.dot(v_p, normal))
    speeds = [s.name for s in system.speeds]
    solved_for = list(system.contact_speeds)
    if len(solved_for) != len(rows):
        raise ModelError(
            f"the contacts give {len(rows)} conditions; name as many contact_speeds, "
            f"not {len(solved_for)}"
        )
    overlap = [s for s in solved_for if s in already_dependent or s not in speeds]
    if overlap:
        raise ModelError(f"contact_speeds {', '.join(overlap)}: not free speeds of the system")
    # Substitute the explicit constraints' dependent speeds, then E = A_D p_D + A_I p_I = 0.
    explicit = {c.dependent: c for c in system.constraints}
    free = [s for s in speeds if s not in explicit and s not in solved_for]
    scope = {**q, **{s: pf[s] for s in free}}
    sub_from = [pf[d] for d in explicit]
    sub_to = [explicit[d].expression(scope) for d in explicit]
    eqs = ca.vertcat(*rows)
    if sub_from:
        eqs = ca.substitute(eqs, ca.vertcat(*sub_from), ca.vertcat(*sub_to))
    p_d = ca.vertcat(*[pf[s] for s in solved_for])
    p_i = ca.vertcat(*[pf[s] for s in free])
    a_d, a_i = ca.jacobian(eqs, p_d), ca.jacobian(eqs, p_i)
    if ca.depends_on(ca.vertcat(a_d.reshape((-1, 1)), a_i.reshape((-1, 1))), ca.vertcat(p_d, p_i)):
        raise ModelError("the rolling conditions are not linear in the speeds")
    solution = ca.solve(a_d, -(a_i @ p_i))
    return [
        Constraint(name, lambda _s, e=solution[k]: e, f"rolling contact: {name}")
        for k, name in enumerate(solved_for)
    ]


def _zero(e) -> bool:
    if isinstance(e, int | float):
        return e == 0
    return ca.SX(e).is_zero()


def _inverse_of_speed_change(speed_names, independent, constraints, ind_syms, pf):
    """Tinv with p_new = Tinv p_full: independent speeds unchanged, c_d = p_d - A_d p_ind."""
    rows = [pf[s] for s in independent]
    for con in constraints:
        rows.append(pf[con.dependent] - con.expression(ind_syms))
    pf_vec = ca.vertcat(*[pf[s] for s in speed_names])
    return ca.jacobian(ca.vertcat(*rows), pf_vec)


def _transform_structure(gamma, Tmat, Tinv, n):
    """Structure coefficients in the new speeds: g'^f_ac = Tinv_fe g^e_bd T_ba T_dc (a
    coordinate-free change of speeds; coordinate-dependent ones are projected instead)."""
    out = [[[ca.SX(0) for _ in range(n)] for _ in range(n)] for _ in range(n)]
    entries = [
        (e, b, d, gamma[e][b][d])
        for e in range(n)
        for b in range(n)
        for d in range(n)
        if not _zero(gamma[e][b][d])
    ]
    for f in range(n):
        for a in range(n):
            for c in range(n):
                acc = ca.SX(0)
                for e, b, d, val in entries:
                    acc = acc + Tinv[f, e] * val * Tmat[b, a] * Tmat[d, c]
                out[f][a][c] = acc
    return out


def _jacobian_x(
    f: ca.SX, x: ca.SX, args: list[ca.SX], M: ca.SX, rhs: ca.SX, n_coords: int
) -> ca.SX:
    """∂f/∂x for f = (q̇, M⁻¹ rhs): CasADi's differentiation of f, or the derivative through
    the inverse, ∂ṗ/∂x = M⁻¹ (∂rhs/∂x − ∂M/∂x · ṗ), which reuses the solve of f (with the
    closed-form 2x2 inverse: its one reciprocal determinant) — whichever has fewer operations
    together with f. The second has the first's sparsity (an entry the differentiation finds
    structurally zero is identically zero)."""
    by_differentiation = ca.jacobian(f, x)
    pdot = f[n_coords:]
    held = ca.SX.sym("held", pdot.numel())
    dM_pdot = ca.substitute(ca.jacobian(M @ held, x), held, ca.densify(pdot))
    through_inverse = ca.vertcat(
        by_differentiation[:n_coords, :], solve_spd(M, ca.jacobian(rhs, x) - dM_pdot)
    )
    through_inverse = ca.project(through_inverse, by_differentiation.sparsity())

    def cost(jac: ca.SX) -> int:
        return operations(ca.Function("f_jac_x", args, [f, jac], {"cse": True}))

    return min((through_inverse, by_differentiation), key=cost)
