"""Canonical forms of the derived coefficients: what a careful person writes by hand.

The Hamel derivation builds M, C p, F and Q as CasADi expressions straight from the body
kinematics, and CasADi does not simplify: the pendulum's mass-matrix entry comes out as
m2 (b² cos²φ + b² sin²φ) + I2_yy, and C p carries products that cancel in pairs. Each entry is
rewritten here as a polynomial in the state, the inputs and the sine and cosine of each angle,
reduced by sin² + cos² = 1, its terms grouped by their state monomial with the parameter
coefficients factored — m2 b² + I2_yy, (I2_xx − I2_zz + m2 b²) w_z² sin φ cos φ — using sympy
for the algebra. An entry is replaced when the rewrite has no more operations (at equal size
the rewrite wins: its products share their parameter factors with the other entries); entries
too large to expand cheaply (the bicycle's) are kept as derived. The rewrite is exact algebra, so
the values agree to rounding (the modeling tests compare every model with its other routes).
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import casadi as ca

if TYPE_CHECKING:
    import sympy as sp

# Entries with more expression nodes than this are left as derived: expanding products of sums
# explodes (a 384-node entry of the bicycle did not finish in minutes; vehicle8's largest has 51).
MAX_NODES = 150
# ... and so are those whose expansion has more terms than this.
MAX_TERMS = 400


@functools.cache
def _sympy():
    """sympy and CasADi's operations in it, imported on first use: `import sympy` takes ~2 s,
    which every `python -m twv_modeling` run that derives no multibody model would pay."""
    import sympy

    unary = {
        ca.OP_NEG: lambda a: -a,
        ca.OP_SIN: sympy.sin,
        ca.OP_COS: sympy.cos,
        ca.OP_SQ: lambda a: a**2,
        ca.OP_SQRT: sympy.sqrt,
        ca.OP_TWICE: lambda a: 2 * a,
    }
    binary = {
        ca.OP_ADD: lambda a, b: a + b,
        ca.OP_SUB: lambda a, b: a - b,
        ca.OP_MUL: lambda a, b: a * b,
        ca.OP_DIV: lambda a, b: a / b,
    }
    return sympy, unary, binary


class _UnsupportedError(Exception):
    """An operation the rewrite does not handle: the entry is kept as derived."""


def _to_sympy(e: ca.SX, memo: dict[int, sp.Expr]) -> sp.Expr:
    """`e` as sympy, each shared node converted once (`memo` by node identity: a walk of the
    tree instead of the graph would unfold shared subexpressions exponentially)."""
    sp, unary, binary = _sympy()
    key = e.element_hash()
    if key in memo:
        return memo[key]
    if e.is_symbolic():
        out = sp.Symbol(e.name())
    elif e.is_constant():
        v = float(e)
        out = sp.Integer(int(v)) if v.is_integer() else sp.Float(v)
    else:
        op = e.op()
        args = [_to_sympy(e.dep(i), memo) for i in range(e.n_dep())]
        if op in unary and len(args) == 1:
            out = unary[op](args[0])
        elif op in binary and len(args) == 2:
            out = binary[op](*args)
        else:
            raise _UnsupportedError(op)
    memo[key] = out
    return out


def _signed_product(x: sp.Expr, env: dict[str, ca.SX], params: set[str]) -> tuple[bool, ca.SX]:
    """A product as (negative, |product|), its factors ordered so that products share their
    prefixes: the number (its sign goes to the sum the product is a term of), the plain symbols
    (states, inputs), the parameter factors as one node — each distinct one once, in name order,
    then the repeats: `b m2` is one node that every entry shares, `m2 b²` is `(b m2) b` — then
    the rest (sums, sines, cosines). So −2 m2 b w_x w_z cos φ and 2 w_x w_z (I2_xx − I2_zz + m2 b²)
    sin φ cos φ both start from the node 2 w_x w_z. A sum factor is taken with the sign sympy
    calls canonical (`could_extract_minus_sign` tells f from −f), so (I2_zz − I2_xx − m2 b²) is
    −(I2_xx − I2_zz + m2 b²) and shares the coefficient node another entry built. (vehicle8's
    f, f + ∂f/∂x, f and J·W: 84 / 210 / 507 operations with the parameters first and signs in
    the factors, 79 / 206 / 511 so.)"""
    number, symbols, distinct, repeats, rest = [], [], [], [], []
    negative = False
    for a in x.args:
        base, n = a.as_base_exp()
        if a.is_Number:
            negative ^= bool(a < 0)
            if abs(a) != 1:
                number.append(abs(a))
        elif base.is_Symbol and base.name in params and n.is_Integer and n > 0:
            distinct.append(base.name)
            repeats += [base.name] * (int(n) - 1)
        elif a.is_Symbol:
            symbols.append(a)
        elif a.is_Add and a.could_extract_minus_sign():
            negative = not negative
            rest.append(-a)
        else:
            rest.append(a)
    factors = [ca.SX(float(v)) for v in number]
    factors += [env[a.name] for a in symbols]
    names = sorted(distinct) + sorted(repeats)
    if names:
        coefficient = env[names[0]]
        for name in names[1:]:
            coefficient = coefficient * env[name]
        factors.append(coefficient)
    factors += [_to_casadi(a, env, params) for a in rest]
    out = factors[0] if factors else ca.SX(1.0)
    for f in factors[1:]:
        out = out * f
    return negative, out


def _to_casadi(x: sp.Expr, env: dict[str, ca.SX], params: set[str]) -> ca.SX:
    sp = _sympy()[0]
    if x.is_Symbol:
        return env[x.name]
    if x.is_Number:
        return ca.SX(float(x))
    if x.is_Mul:
        negative, out = _signed_product(x, env, params)
        return -out if negative else out
    if x.is_Add:
        out = None
        terms = [
            _signed_product(a, env, params) if a.is_Mul else (False, _to_casadi(a, env, params))
            for a in x.args
        ]
        # A positive term first, where there is one: a sum that starts with a subtraction
        # needs a negation more.
        terms.sort(key=lambda t: t[0])
        for negative, term in terms:
            if out is None:
                out = -term if negative else term
            else:
                out = out - term if negative else out + term
        return out
    if x.is_Pow:
        base, n = x.args
        b = _to_casadi(base, env, params)
        if n.is_Integer and n > 0:
            out = b
            for _ in range(int(n) - 1):
                out = out * b
            return out
        if n == -1:
            return 1 / b
        if n == sp.Rational(1, 2):
            return ca.sqrt(b)
        raise _UnsupportedError(x)
    if isinstance(x, sp.sin):
        return ca.sin(_to_casadi(x.args[0], env, params))
    if isinstance(x, sp.cos):
        return ca.cos(_to_casadi(x.args[0], env, params))
    raise _UnsupportedError(x)


def _rewrite(x: sp.Expr, params: set[str]) -> sp.Expr | None:
    """The canonical polynomial form of `x`, or None when it is not a polynomial in the state,
    inputs and the trigonometric functions of plain symbols (a division by the state, say)."""
    sp = _sympy()[0]
    trig: list[tuple[sp.Symbol, sp.Symbol]] = []
    to_trig, back = {}, {}
    for f in sorted(x.atoms(sp.sin, sp.cos), key=sp.default_sort_key):
        arg = f.args[0]
        if not arg.is_Symbol:
            return None
        s, c = sp.Symbol(f"_sin_{arg.name}"), sp.Symbol(f"_cos_{arg.name}")
        if (s, c) not in trig:
            trig.append((s, c))
            to_trig.update({sp.sin(arg): s, sp.cos(arg): c})
            back.update({s: sp.sin(arg), c: sp.cos(arg)})
    x = sp.expand(x.xreplace(to_trig))
    if x.is_Add and len(x.args) > MAX_TERMS:
        return None
    free = sorted((s for s in x.free_symbols if s.name not in params), key=sp.default_sort_key)
    trig_syms = [t for pair in trig for t in pair]
    states = [s for s in free if s not in trig_syms]
    gens = states + [t for t in trig_syms if x.has(t)]
    if not gens:
        return sp.factor(x)
    if not x.is_polynomial(*gens):
        return None
    # sin² = 1 − cos², angle by angle: the remainder has each sine to the first power at most.
    for s, c in trig:
        if x.has(s):
            x = sp.expand(sp.rem(x, s**2 + c**2 - 1, s))
    poly = sp.Poly(x, *gens)
    n = len(states)
    groups: dict[tuple[int, ...], sp.Expr] = {}
    for monom, coeff in poly.terms():
        trig_part = sp.Mul(*[g**k for g, k in zip(gens[n:], monom[n:], strict=True)])
        groups[monom[:n]] = groups.get(monom[:n], sp.Integer(0)) + coeff * trig_part
    out = sp.Integer(0)
    for monom, inner in groups.items():
        inner = sp.collect(sp.expand(inner), gens[n:], func=sp.factor)
        out += sp.Mul(*[g**k for g, k in zip(gens[:n], monom, strict=True)]) * inner
    return out.xreplace(back)


def canonical_entry(e: ca.SX, params: set[str], env: dict[str, ca.SX]) -> ca.SX:
    """`e` rewritten (see the module doc) when that has no more operations, else `e`."""
    if e.nnz() == 0 or e.is_zero() or e.is_constant() or e.is_symbolic():
        return e
    if ca.n_nodes(e) > MAX_NODES:
        return e
    try:
        rewritten = _rewrite(_to_sympy(e, {}), params)
        if rewritten is None:
            return e
        out = ca.cse(_to_casadi(rewritten, env, params))
    except _UnsupportedError:
        return e
    # Equal size: the rewrite, whose products share their parameter factors with the others.
    return out if ca.n_nodes(out) <= ca.n_nodes(ca.cse(e)) else e


def canonical(m: ca.SX, params: set[str], env: dict[str, ca.SX]) -> ca.SX:
    """Every entry of the matrix `m` through [`canonical_entry`]; structural zeros stay."""
    out = ca.SX(m.size1(), m.size2())
    for i in range(m.size1()):
        for j in range(m.size2()):
            e = m[i, j]
            if not (e.nnz() == 0 or e.is_zero()):
                out[i, j] = canonical_entry(e, params, env)
    return out
