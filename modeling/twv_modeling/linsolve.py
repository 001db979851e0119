"""Symbolic solve of the mass-matrix system that keeps structural zeros.

An LDL^T factorization without pivoting (M is symmetric positive definite) that never builds a
term for a structurally zero entry: a block-diagonal M (the vehicles' pitch/forward and
lateral/yaw blocks) stays block-diagonal, so the symbolic expressions stay small.

Each update subtracts L_ik U_jk, where U_jk = L_jk d_k is the entry before its division by the
pivot (kept, not recomputed): one product instead of L_ik L_jk d_k's two, and a shorter chain
from the angles to the next pivot (vehicle8: 2 operations fewer in f and in f + df/dx, 4 fewer
dependent operations before the Jacobian's last entry).
"""

from __future__ import annotations

import casadi as ca


def is_structural_zero(e: ca.SX) -> bool:
    return e.nnz() == 0 or e.is_zero()


def solve_spd(M: ca.SX, b: ca.SX) -> ca.SX:
    """Return M^{-1} b for a symmetric positive definite symbolic M."""
    n = M.size1()
    A = [[ca.SX(M[i, j]) for j in range(n)] for i in range(n)]
    L: list[list[ca.SX | None]] = [[None] * n for _ in range(n)]
    U: list[list[ca.SX | None]] = [[None] * n for _ in range(n)]  # U[i][j] = L[i][j] d[j]
    d: list[ca.SX] = []
    for j in range(n):
        s = A[j][j]
        for k in range(j):
            if L[j][k] is not None:
                s = s - L[j][k] * U[j][k]
        d.append(s)
        for i in range(j + 1, n):
            s = A[i][j]
            for k in range(j):
                if L[i][k] is not None and U[j][k] is not None:
                    s = s - L[i][k] * U[j][k]
            if not is_structural_zero(s):
                U[i][j] = s
                L[i][j] = s / d[j]
    y: list[ca.SX] = []
    for i in range(n):
        s = ca.SX(b[i])
        for k in range(i):
            if L[i][k] is not None:
                s = s - L[i][k] * y[k]
        y.append(s)
    x: list[ca.SX | None] = [None] * n
    for i in reversed(range(n)):
        s = y[i] / d[i]
        for k in range(i + 1, n):
            if L[k][i] is not None:
                s = s - L[k][i] * x[k]
        x[i] = s
    return ca.vertcat(*x)
