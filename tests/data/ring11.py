"""A ring of eleven linear first-order states, x_i' = -x_i + a x_(i+1 mod 11): a model larger
than any shipped one (the interpreter dispatches up to 12 states), whose Lyapunov exponents are
known in closed form: the real parts -1 + a cos(2 pi k / 11) of the circulant's eigenvalues."""

from twv_modeling.explicit import ExplicitModel
from twv_modeling.params import Param

N = 11


def model():
    m = ExplicitModel(
        "ring11",
        states=[(f"x{i}", "1") for i in range(N)],
        params=[Param("a", "1", default=0.5, description="coupling to the next state")],
        description="Ring of eleven coupled linear states (an interpreter-size test model).",
    )
    x = m.x_parts
    (a,) = m.p_parts
    m.rhs = [-x[i] + a * x[(i + 1) % N] for i in range(N)]
    return m
