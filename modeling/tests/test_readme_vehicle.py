"""The modeling guide's example of a new vehicle (docs/src/modeling.md: a rolling disc from
bodies, joints and a generated rolling contact) runs as written, and is the same vehicle as the
disc whose rolling constraints are typed in by hand (test_rolling_disc.py)."""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import numpy as np
from test_rolling_disc import CONTACT, VALUES

README = Path(__file__).resolve().parents[2] / "docs" / "src" / "modeling.md"


def _example() -> str:
    text = README.read_text(encoding="utf-8")
    start = text.index("# README example: a new vehicle")
    return text[start : text.index("```", start)]


def test_the_readme_vehicle_is_the_hand_constrained_disc(capsys):
    scope: dict = {}
    exec(compile(_example(), "docs/src/modeling.md", "exec"), scope)  # noqa: S102 - the README's own code
    printed = capsys.readouterr().out
    model = scope["model"]
    names = [s.name for s in model.states]
    assert printed.strip() == str(names)
    f = ca.Function("f", [model.x, model.p], [model.expressions["f"]])
    p = [VALUES["m"], VALUES["R"], VALUES["g"]]
    hand_names, hand_f = CONTACT
    assert sorted(names) == sorted(hand_names)
    rng = np.random.default_rng(11)
    for _ in range(30):
        state = dict(zip(names, rng.uniform(-2, 2, len(names)), strict=True))
        state["phi"] = rng.uniform(-1.2, 1.2)
        got = dict(zip(names, np.array(f([state[n] for n in names], p)).ravel(), strict=True))
        want = dict(zip(hand_names, hand_f("f", [state[n] for n in hand_names]), strict=True))
        for n in names:
            assert abs(got[n] - want[n]) <= 1e-12 * (1 + abs(want[n])), n
    # Its steady motion: upright rolling, stable above v^2 = g R / 3.
    steady = ca.Function("s", [model.p], [model.expressions["steady"]])
    unit = np.array(steady(p)).ravel()
    jac = ca.Function("j", [model.x, model.p], [ca.jacobian(model.expressions["f"], model.x)])
    modes = [names.index(n) for n in ("phi", "w_phi", "w_psi")]
    critical = math.sqrt(VALUES["g"] * VALUES["R"] / 3)

    def growth(v):
        a = np.array(jac(v * unit, p))[np.ix_(modes, modes)]
        return max(np.linalg.eigvals(a).real)

    assert growth(0.9 * critical) > 1e-3
    assert abs(growth(1.1 * critical)) <= 1e-9
