"""The symbolic mass-matrix solve and the Jacobian through the inverse.

The block-wise solve (closed-form 1x1 and 2x2 blocks, LDL^T for larger ones) must equal a
numerical solve for any SPD matrix with that block structure; the Jacobian the multibody
derivation exports (through M's inverse where that has fewer operations) must equal CasADi's
differentiation of f, a second route to the same numbers.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from twv_modeling.derived import operations
from twv_modeling.linsolve import coupled_blocks, solve_spd
from twv_modeling.registry import build


def _block_spd(rng: np.random.Generator, sizes: list[int], order: list[int]) -> np.ndarray:
    """An SPD matrix with diagonal blocks of `sizes`, its indices permuted by `order`."""
    n = sum(sizes)
    M = np.zeros((n, n))
    start = 0
    for size in sizes:
        A = rng.normal(size=(size, size))
        M[start : start + size, start : start + size] = A @ A.T + size * np.eye(size)
        start += size
    return M[np.ix_(order, order)]


def _symbolic(M: np.ndarray) -> tuple[ca.SX, ca.SX]:
    """M with a symbol at each nonzero (zeros stay structural) and the symbols' vector."""
    n = M.shape[0]
    S, symbols = ca.SX(n, n), []
    for i in range(n):
        for j in range(i + 1):
            if M[i, j] != 0.0:
                s = ca.SX.sym(f"m{i}{j}")
                S[i, j] = s
                S[j, i] = s
                symbols.append((s, M[i, j]))
    return S, symbols


@pytest.mark.parametrize(
    "sizes",
    [[1], [2], [3], [2, 2], [1, 2, 3], [4, 1, 2], [2, 1, 1, 2]],
)
def test_the_block_wise_solve_equals_a_numerical_solve(sizes):
    rng = np.random.default_rng(sum(sizes) * 7 + len(sizes))
    n = sum(sizes)
    order = list(rng.permutation(n))
    M = _block_spd(rng, sizes, order)
    S, symbols = _symbolic(M)
    B = rng.normal(size=(n, 3))
    b_sym = ca.SX.sym("b", n, 3)
    x = ca.Function("x", [ca.vertcat(*[s for s, _ in symbols]), b_sym], [solve_spd(S, b_sym)])(
        [v for _, v in symbols], B
    )
    want = np.linalg.solve(M, B)
    assert np.abs(np.array(x) - want).max() <= 1e-12 * np.abs(want).max()
    # The blocks found are the ones built, whatever the permutation.
    found = sorted(len(b) for b in coupled_blocks(S))
    assert found == sorted(sizes)


def test_a_2x2_block_divides_by_its_determinant_only():
    # One denominator: the IR's lowering turns it into one reciprocal for both unknowns.
    a, b, c, r0, r1 = (ca.SX.sym(n) for n in "abcrs")
    M = ca.blockcat([[a, b], [b, c]])
    fn = ca.Function("x", [a, b, c, r0, r1], [solve_spd(M, ca.vertcat(r0, r1))], {"cse": True})
    denominators = set()
    for k in range(fn.n_instructions()):
        if fn.instruction_id(k) == ca.OP_DIV:
            denominators.add(fn.instruction_input(k)[1])
        elif fn.instruction_id(k) == ca.OP_INV:
            denominators.add(fn.instruction_input(k)[0])
    assert len(denominators) == 1
    x = np.array(fn(4.0, 1.0, 3.0, 1.0, 2.0)).ravel()
    assert np.allclose(x, np.linalg.solve([[4.0, 1.0], [1.0, 3.0]], [1.0, 2.0]), rtol=1e-15)


@pytest.mark.parametrize("name", ["vehicle8", "vehicle7", "segway7"])
def test_the_exported_jacobian_equals_casadis_differentiation(name):
    model = build(name)
    f = model.expressions["f"]
    args = [model.x, model.u, model.p]
    ours = ca.Function("ours", args, [model.jacobian_x()])
    theirs = ca.Function("theirs", args, [ca.jacobian(f, model.x)])
    assert model.jacobian_x().sparsity() == ca.jacobian(f, model.x).sparsity()
    rng = np.random.default_rng(5)
    p = [prm.default for prm in model.params]
    for _ in range(50):
        x = rng.uniform(-2, 2, model.x.numel())
        u = rng.uniform(-50, 50, model.u.numel())
        want, got = np.array(theirs(x, u, p)), np.array(ours(x, u, p))
        assert np.abs(got - want).max() <= 1e-12 * max(1.0, np.abs(want).max())


def test_the_form_with_fewer_operations_is_exported():
    # vehicle8: through the inverse, 209 operations with f against 230 by differentiation.
    model = build("vehicle8")
    assert model.jac_x is not None
    f, args = model.expressions["f"], [model.x, model.u, model.p]

    def ops(jac):
        return operations(ca.Function("f_jac_x", args, [f, jac], {"cse": True}))

    assert ops(model.jacobian_x()) < ops(ca.jacobian(f, model.x))
