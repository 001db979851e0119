"""The Henon-Heiles system: a Hamiltonian reference for Lyapunov spectra (exponents in +- pairs,
sum zero). H = (p_x^2 + p_y^2)/2 + (x^2 + y^2)/2 + x^2 y - y^3/3."""

from twv_modeling.explicit import ExplicitModel


def model():
    m = ExplicitModel(
        "henon_heiles",
        states=[("x", "1"), ("y", "1"), ("p_x", "1"), ("p_y", "1")],
        description="Henon-Heiles (1964) galactic potential, Hamiltonian with two degrees of "
        "freedom.",
    )
    x, y, px, py = m.x_parts
    m.rhs = [px, py, -x - 2 * x * y, -y - x * x + y * y]
    m.energy = (px * px + py * py) / 2 + (x * x + y * y) / 2 + x * x * y - y * y * y / 3
    return m
