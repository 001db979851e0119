"""Balancing the bicycle by steering, from Python: `twv.steer`'s closed-loop eigenvalues against
the linear benchmark equations of Meijaard et al. (2007) computed from the 25 parameters by the
modeling package's closed-form Appendix A (`twv_modeling.whipple_benchmark`: a second derivation,
not twv's), with the feedback T_delta = K (phi, delta, phi', delta') substituted; and a tuned
schedule read as data."""

from __future__ import annotations

import numpy as np
import pytest
from twv_modeling.whipple_benchmark import benchmark_matrices, read_parameters

import twv

GAINS = {"k_phi": 40.0, "k_delta": -25.0, "k_phi_dot": 12.0, "k_delta_dot": -4.0}


def benchmark_closed_loop(v: float, k: np.ndarray) -> np.ndarray:
    b = benchmark_matrices(read_parameters())
    a = b.state_matrix(v)
    minv = np.linalg.inv(b.M)
    # f = (0, T_delta) with T_delta = K x: the steer column of M^-1 times K on the rates' rows.
    a[2:, :] += np.outer(minv[:, 1], k)
    ev = np.linalg.eigvals(a)
    return ev[np.lexsort((ev.imag, ev.real))]


@pytest.mark.parametrize("v", [1.0, 3.0, 5.0, 7.0])
def test_given_gains_give_the_benchmark_closed_loop(v):
    r = twv.steer(twv.Model("whipple"), speed=v, gains=GAINS)
    (ours,) = r.closed_loop_eigenvalues
    ours = ours[np.lexsort((ours.imag, ours.real))]
    k = np.array([GAINS[g] for g in ("k_phi", "k_delta", "k_phi_dot", "k_delta_dot")])
    theirs = benchmark_closed_loop(v, k)
    assert np.all(np.abs(ours - theirs) <= 1e-10 * np.maximum(1.0, np.abs(theirs))), (ours, theirs)
    # Unsteered, the same path gives the open loop.
    (open_loop,) = r.open_loop_eigenvalues
    open_loop = open_loop[np.lexsort((open_loop.imag, open_loop.real))]
    assert np.allclose(open_loop, benchmark_closed_loop(v, np.zeros(4)), rtol=1e-10, atol=1e-10)


def test_a_schedule_is_data():
    r = twv.steer(twv.Model("whipple"), speed="2:6:2")
    assert r.ok and r.met.all() and r.gains.shape == (3, 4)
    df = r.to_pandas()
    assert list(df["speed"]) == [2.0, 4.0, 6.0]
    assert (df["disk_phase_margin_deg"] >= 45.0 - 1e-7).all()
    # Steering into the fall: the lean gain is positive at every speed.
    assert (r.gains[:, 0] > 0).all()


def test_a_ride_steered_by_the_schedules_gains_recovers():
    r = twv.steer(twv.Model("whipple"), speed=3)
    k = dict(zip(("k_phi", "k_delta", "k_phi_dot", "k_delta_dot"), r.gains[0], strict=True))
    ride = twv.ride(twv.Model("whipple"), speed=3, perturb="w_phi=0.5", steer_gains=k)
    assert ride.raw["verdict"] == "recovered", ride.summary
    unsteered = twv.ride(twv.Model("whipple"), speed=3, perturb="w_phi=0.5")
    assert unsteered.raw["verdict"] == "fell", unsteered.summary


def test_a_steer_map_is_the_benchmark_closed_loop_at_every_cell():
    r = twv.steer_map(
        twv.Model("whipple"),
        speed="1:7:4",
        gain="k_phi_dot",
        values="-10:30:5",
        gains={"k_phi": 10.0},
    )
    assert r.abscissa.shape == (5, 4)
    for j, x in enumerate(r.values):
        for i, v in enumerate(r.speeds):
            k = np.array([10.0, 0.0, x, 0.0])
            theirs = benchmark_closed_loop(v, k).real.max()
            assert abs(r.abscissa[j, i] - theirs) <= 1e-10 * max(1.0, abs(theirs)), (v, x)
    assert (r.stable == (r.abscissa < 0)).all()
    assert r.weave_speed == pytest.approx(4.2924, abs=1e-4)


def test_a_gain_by_gain_steer_map_is_the_benchmark_closed_loop_at_its_speed():
    r = twv.steer_map(
        twv.Model("whipple"),
        speed=2.5,
        gain="k_phi_dot",
        values="-10:30:5",
        against="k_delta",
        against_values="-20:10:4",
        gains={"k_phi": 10.0},
    )
    assert r.abscissa.shape == (5, 4)
    assert list(r.x) == list(r.against_values) and list(r.speeds) == [2.5]
    for j, y in enumerate(r.values):
        for i, x in enumerate(r.x):
            theirs = benchmark_closed_loop(2.5, np.array([10.0, x, y, 0.0])).real.max()
            assert abs(r.abscissa[j, i] - theirs) <= 1e-10 * max(1.0, abs(theirs)), (x, y)
    unsteered = benchmark_closed_loop(2.5, np.zeros(4)).real.max()
    assert r.unsteered_abscissa == pytest.approx(unsteered, abs=1e-10)


@pytest.mark.parametrize(("v", "verdict"), [(2.5, "unstable"), (5.0, "self-stable")])
def test_a_one_speed_maps_unsteered_verdict_follows_the_self_stable_band(v, verdict):
    """Below the weave speed (4.29 m/s) the unsteered bicycle is unstable, inside the band
    (to 6.02 m/s) self-stable: the summary's word follows the open loop's abscissa."""
    r = twv.steer_map(twv.Model("whipple"), speed=v, values="0:10:3")
    assert (r.unsteered_abscissa < 0) == (verdict == "self-stable")
    assert f"at {v:g} m/s it is {verdict} " in r.summary, r.summary
