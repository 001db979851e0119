"""Structural identities of the Poincare equations M p_dot + C p + F = Q."""

import casadi as ca
import numpy as np
from conftest import random_states

from twv_modeling.registry import build


def _mdot_function(name):
    """p^T C p and p^T Mdot p / 2 with Mdot = dM/dq q_dot, q_dot = V(q) p from f."""
    m = build(name)
    M, Cp, f = m.expressions["M"], m.expressions["Cp"], m.expressions["f"]
    ns = M.size1()
    nq = m.x.numel() - ns
    q, p = m.x[:nq], m.x[nq:]
    qdot = f[:nq]
    Mdot = ca.reshape(ca.jacobian(ca.vec(M), q) @ qdot, ns, ns)
    return ca.Function("id", [m.x, m.u, m.p], [ca.dot(p, Cp), 0.5 * ca.dot(p, Mdot @ p)])


def test_gyroscopic_terms_do_no_work(vehicle, params):
    fn = _mdot_function(vehicle.model.name)
    xs, us = random_states(vehicle, 50)
    for x, u in zip(xs, us, strict=True):
        pcp, half = (float(v) for v in fn(x, u, params))
        assert abs(pcp - half) <= 1e-12 * max(1.0, abs(half))


def test_mass_matrix_symmetric_positive_definite(vehicle, params):
    xs, us = random_states(vehicle, 50)
    for x, u in zip(xs, us, strict=True):
        M = vehicle("M", x, u, params)
        M = np.atleast_2d(M)
        assert np.allclose(M, M.T, rtol=0, atol=1e-14 * np.abs(M).max())
        assert np.linalg.eigvalsh(M).min() > 0


def test_state_equation_solves_poincare_form(vehicle, params):
    """f's speed rows are M^-1 (Q - Cp - F): check the residual of the solved system."""
    xs, us = random_states(vehicle, 50)
    ns = vehicle.model.expressions["M"].size1()
    for x, u in zip(xs, us, strict=True):
        pdot = vehicle("f", x, u, params)[-ns:]
        M = vehicle("M", x, u, params)
        rhs = vehicle("Q", x, u, params) - vehicle("Cp", x, u, params) - vehicle("F", x, u, params)
        assert np.allclose(M @ pdot, rhs, rtol=1e-12, atol=1e-12 * np.abs(rhs).max())
