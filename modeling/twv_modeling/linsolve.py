"""Symbolic solve of the mass-matrix system that keeps structural zeros.

M (symmetric positive definite) is split into its coupled blocks: indices linked by a chain of
structurally nonzero entries (the vehicles' pitch/forward and lateral/yaw pairs). Blocks never
exchange terms, so each is solved on its own:

- a 1x1 block by one division;
- a 2x2 block [a b; b c] in closed form, x = [c -b; -b a] r / det with det = a c - b^2: one
  reciprocal shared by both unknowns and by every right-hand side (the Jacobian's columns). Its
  chain from the entries to the solution is one division long; an LDL^T factorisation of the
  same block has two divisions in sequence (the second pivot waits for the first), which
  vehicle8's J.W kernel measurably waits on;
- a larger block by an LDL^T factorisation without pivoting that never builds a term for a
  structurally zero entry. Each update subtracts L_ik U_jk, where U_jk = L_jk d_k is the entry
  before its division by the pivot (kept, not recomputed): one product instead of L_ik L_jk
  d_k's two.
"""

from __future__ import annotations

import casadi as ca


def is_structural_zero(e: ca.SX) -> bool:
    return e.nnz() == 0 or e.is_zero()


def coupled_blocks(M: ca.SX) -> list[list[int]]:
    """M's coupled index sets, each in increasing order, ordered by their first index."""
    n = M.size1()
    block_of = list(range(n))

    def root(i: int) -> int:
        while block_of[i] != i:
            i = block_of[i]
        return i

    for i in range(n):
        for j in range(i):
            if not is_structural_zero(ca.SX(M[i, j])):
                block_of[max(root(i), root(j))] = min(root(i), root(j))
    blocks: dict[int, list[int]] = {}
    for i in range(n):
        blocks.setdefault(root(i), []).append(i)
    return list(blocks.values())


def solve_spd(M: ca.SX, B: ca.SX) -> ca.SX:
    """Return M^{-1} B for a symmetric positive definite symbolic M and a vector or matrix B."""
    n, m = M.size1(), B.size2()
    X = ca.SX(n, m)
    for block in coupled_blocks(M):
        A = [[ca.SX(M[i, j]) for j in block] for i in block]
        rhs = [[ca.SX(B[i, c]) for c in range(m)] for i in block]
        solve = {1: _solve_1x1, 2: _solve_2x2}.get(len(block), _solve_ldl)
        for row, i in zip(solve(A, rhs), block, strict=True):
            for c, v in enumerate(row):
                if not is_structural_zero(v):
                    X[i, c] = v
    return X


def _solve_1x1(A: list[list[ca.SX]], rhs: list[list[ca.SX]]) -> list[list[ca.SX]]:
    return [[r / A[0][0] for r in rhs[0]]]


def _solve_2x2(A: list[list[ca.SX]], rhs: list[list[ca.SX]]) -> list[list[ca.SX]]:
    (a, b), (_, c) = A
    inv_det = 1 / (a * c - b * b)
    first = [(c * r0 - b * r1) * inv_det for r0, r1 in zip(*rhs, strict=True)]
    second = [(a * r1 - b * r0) * inv_det for r0, r1 in zip(*rhs, strict=True)]
    return [first, second]


def _solve_ldl(A: list[list[ca.SX]], rhs: list[list[ca.SX]]) -> list[list[ca.SX]]:
    n = len(A)
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
    columns = [_ldl_column(L, d, col) for col in zip(*rhs, strict=True)]
    return [list(row) for row in zip(*columns, strict=True)]


def _ldl_column(L: list[list[ca.SX | None]], d: list[ca.SX], b: tuple[ca.SX, ...]) -> list[ca.SX]:
    """L D L^T x = b by forward and back substitution."""
    n = len(d)
    y: list[ca.SX] = []
    for i in range(n):
        s = b[i]
        for k in range(i):
            if L[i][k] is not None:
                s = s - L[i][k] * y[k]
        y.append(s)
    x: list[ca.SX] = [ca.SX(0)] * n
    for i in reversed(range(n)):
        s = y[i] / d[i]
        for k in range(i + 1, n):
            if L[k][i] is not None:
                s = s - L[k][i] * x[k]
        x[i] = s
    return x
