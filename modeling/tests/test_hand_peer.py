"""The benchmark's second C peer — vehicle8 written by hand in CasADi (Cramer's rule on the two
2x2 blocks of the mass matrix) — is the same vehicle as the derivation, and the export counts
the operations of both."""

import json

import casadi as ca
import numpy as np
from conftest import numeric, random_states

from twv_modeling.cgen import export_c
from twv_modeling.hand_peer import vehicle8_by_hand


def test_the_hand_formulation_is_the_derived_vehicle():
    model = numeric("vehicle8")
    m = model.model
    hand = ca.Function("hand", [m.x, m.u, m.p], [vehicle8_by_hand(m)])
    p = [prm.default for prm in m.params]
    xs, us = random_states(model, 200, seed=5)
    for x, u in zip(xs, us, strict=True):
        want = model("f", x, u, p)
        got = np.array(hand(x, u, p)).ravel()
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_export_writes_both_peers_with_their_operation_counts(tmp_path):
    m = numeric("vehicle8").model
    export_c(m, tmp_path)
    export_c(m, tmp_path, vehicle8_by_hand(m), tag="_hand")
    own = json.loads((tmp_path / "vehicle8_ops.json").read_text())
    hand = json.loads((tmp_path / "vehicle8_hand_ops.json").read_text())
    assert set(own) == set(hand) == {"f", "f_jac_x", "f_jw8"}
    assert (tmp_path / "vehicle8_hand_casadi.c").read_text().count("vehicle8_hand_f_jw8") > 0
    # More outputs, more operations, for both.
    for counts in (own, hand):
        assert 0 < counts["f"] < counts["f_jac_x"] < counts["f_jw8"], counts


def test_export_names_jw_by_its_tangents_and_can_leave_out_the_baked_functions(tmp_path):
    m = numeric("lorenz").model
    export_c(m, tmp_path, tangents=3, baked=False)
    counts = json.loads((tmp_path / "lorenz_ops.json").read_text())
    assert set(counts) == {"f", "f_jac_x", "f_jw3"}
    header = (tmp_path / "lorenz_casadi.h").read_text()
    assert "lorenz_f_jw3(" in header and "_baked" not in header
    export_c(m, tmp_path, tangents=2)
    assert "lorenz_f_jw2_baked(" in (tmp_path / "lorenz_casadi.h").read_text()
