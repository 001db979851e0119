"""The closed-form linearised Whipple bicycle against the published benchmark: Meijaard,
Papadopoulos, Ruina & Schwab (2007), Proc. R. Soc. A 463: 1955-1982 — their eq. (5.4) matrices,
Table 2 eigenvalues and self-stable speed range, computed here from their Table 1 parameters
(vehicles/whipple.toml)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from twv_modeling.whipple_benchmark import DEFAULT_FILE, benchmark_matrices, read_parameters

# Meijaard et al. (2007): the eq. (5.4) matrices at the benchmark parameters (K0 without g),
# Table 2's eigenvalues at v = 0, 1, ..., 10 m/s (castering, capsize and the weave pair: a
# complex entry stands for its conjugate pair) and its weave and capsize speeds. One file for
# the Python and the Rust tests.
REFERENCE = json.loads(
    (Path(__file__).resolve().parents[2] / "tests" / "data" / "meijaard2007.json").read_text()
)
PUBLISHED = {k: REFERENCE[k] for k in ("M", "C1", "K0", "K2")}
TABLE2 = {
    int(v): [complex(re, im) if im else re for re, im in row]
    for v, row in REFERENCE["table2"].items()
}
WEAVE, CAPSIZE = REFERENCE["weave_speed"], REFERENCE["capsize_speed"]


@pytest.fixture(scope="module")
def bicycle():
    return benchmark_matrices(read_parameters())


def test_matrices_equal_the_published_ones(bicycle):
    for name, want in PUBLISHED.items():
        got = getattr(bicycle, name)
        want = np.array(want)
        zero = want == 0.0
        assert np.all(got[zero] == 0.0), name
        rel = np.abs(got[~zero] - want[~zero]) / np.abs(want[~zero])
        assert rel.max() <= 1e-12, (name, rel.max())


def _expected(row):
    out = []
    for e in row:
        out.extend([e, e.conjugate()] if isinstance(e, complex) else [e])
    return np.array(out, dtype=complex)


@pytest.mark.parametrize("speed", sorted(TABLE2))
def test_eigenvalues_equal_table_2(bicycle, speed):
    want = _expected(TABLE2[speed])
    got = bicycle.eigenvalues(speed)
    order = lambda z: z[np.lexsort((z.imag, z.real))]  # noqa: E731
    assert np.max(np.abs(order(got) - order(want))) <= 1e-10


def test_self_stable_speed_range(bicycle):
    weave, capsize = bicycle.stable_speed_range()
    assert abs(weave - WEAVE) <= 1e-10
    assert abs(capsize - CAPSIZE) <= 1e-10
    # The verdict flips where the spectral abscissa does: unstable, stable, unstable.
    assert bicycle.spectral_abscissa(3.0) > 0
    assert bicycle.spectral_abscissa(5.0) < 0
    assert bicycle.spectral_abscissa(7.0) > 0
    # At the weave speed the weave pair is on the imaginary axis (Table 2 (a): ±3.43503384866144 i).
    ev = bicycle.eigenvalues(WEAVE)
    pair = ev[np.argsort(-np.abs(ev.imag))][:2]
    assert np.max(np.abs(np.abs(pair.imag) - 3.43503384866144)) <= 1e-10
    assert np.max(np.abs(pair.real)) <= 1e-10


def test_no_stable_range_when_none_exists(bicycle):
    # Without speed the bicycle falls like an inverted pendulum; below the weave speed there is
    # no self-stable interval to find.
    assert bicycle.stable_speed_range(0.0, 4.0) is None


def test_bad_parameter_files_name_the_field(tmp_path):
    text = DEFAULT_FILE.read_text()
    missing = tmp_path / "missing.toml"
    missing.write_text(text.replace("m_F = 3.0", ""))
    with pytest.raises(ValueError, match="missing.toml: missing m_F"):
        read_parameters(missing)
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("m_F = 3.0", 'm_F = "heavy"'))
    with pytest.raises(ValueError, match="m_F = 'heavy' is not a finite number"):
        read_parameters(bad)
    extra = tmp_path / "extra.toml"
    extra.write_text(text + "\nm_X = 1.0\n")
    with pytest.raises(ValueError, match="unknown m_X"):
        read_parameters(extra)
