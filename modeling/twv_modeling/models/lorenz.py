"""The Lorenz system (sigma = 10, rho = 28, beta = 8/3): the explicit-ODE example and a Lyapunov
reference (spectrum about (0.9056, 0, -14.5723))."""

from twv_modeling.explicit import ExplicitModel
from twv_modeling.params import Param


def model():
    m = ExplicitModel(
        "lorenz",
        states=[("x", "1"), ("y", "1"), ("z", "1")],
        params=[
            Param("sigma", "1", default=10.0, description="Prandtl number"),
            Param("rho", "1", default=28.0, description="Rayleigh number ratio"),
            Param("beta", "1", default=8.0 / 3.0, description="geometric factor"),
        ],
        description="Lorenz (1963) convection model.",
    )
    x, y, z = m.x_parts
    sigma, rho, beta = m.p_parts
    m.rhs = [sigma * (y - x), x * (rho - z) - y, x * y - beta * z]
    return m
