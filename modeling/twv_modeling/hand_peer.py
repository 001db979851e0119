"""vehicle8's equations written by hand in CasADi the way a careful user would: M, C p, F and Q
in closed form (the hand model of analysis/src/hand_model/DERIVATION.md), the mass matrix's two
decoupled 2x2 blocks — (w_y, v_x) and (v_y, w_z) — solved by Cramer's rule, `cse` on when
exported. The second C peer of the kernel benchmark (issue: fewer operations from the
derivation): twv's derivation is measured against what a person gets by hand, not only against
its own export.
"""

from __future__ import annotations

import casadi as ca

from .derived import DerivedModel


def vehicle8_by_hand(model: DerivedModel) -> ca.SX:
    """f(x, u, p) of vehicle8 in the model's own symbols (its state, input and parameter
    vectors), so the two exports take the same arguments."""
    names = [p.name for p in model.params]
    par = {n: model.p[i] for i, n in enumerate(names)}
    phi, _x, _y, theta, w_y, v_x, v_y, w_z = (model.x[i] for i in range(8))
    f1, t2 = model.u[0], model.u[1]
    m1, m2, b, g = par["m1"], par["m2"], par["b"], par["g"]
    sp, cp = ca.sin(phi), ca.cos(phi)
    st, ct = ca.sin(theta), ca.cos(theta)
    mt = m1 + m2
    mb = m2 * b
    ip = par["I2_yy"] + mb * b
    k = par["I2_xx"] - par["I2_zz"] + mb * b
    izz = par["I1_zz"] + (par["I2_xx"] + mb * b) * sp * sp + par["I2_zz"] * cp * cp
    # Q - C p - F, by speed.
    r1 = mb * cp * w_z * v_y + k * sp * cp * w_z * w_z + mb * g * sp
    r2 = f1 + mb * sp * (w_y * w_y + w_z * w_z) + mt * w_z * v_y
    r3 = -(2 * mb * cp * w_z * w_y + mt * w_z * v_x)
    r4 = t2 - (2 * k * sp * cp * w_z * w_y + mb * sp * w_z * v_x)
    # Block (w_y, v_x): [[ip, mb cp], [mb cp, mt]]; block (v_y, w_z): [[mt, mb sp], [mb sp, izz]].
    a12, b12 = mb * cp, mb * sp
    det1 = ip * mt - a12 * a12
    det2 = mt * izz - b12 * b12
    return ca.vertcat(
        w_y,
        v_x * ct - v_y * st,
        v_x * st + v_y * ct,
        w_z,
        (mt * r1 - a12 * r2) / det1,
        (ip * r2 - a12 * r1) / det1,
        (izz * r3 - b12 * r4) / det2,
        (mt * r4 - b12 * r3) / det2,
    )
