"""The closed-form linearised Whipple bicycle against the published benchmark: Meijaard,
Papadopoulos, Ruina & Schwab (2007), Proc. R. Soc. A 463: 1955-1982 — their eq. (5.4) matrices,
Table 2 eigenvalues and self-stable speed range, computed here from their Table 1 parameters
(vehicles/whipple.toml)."""

from __future__ import annotations

import numpy as np
import pytest

from twv_modeling.whipple_benchmark import DEFAULT_FILE, benchmark_matrices, read_parameters

# Meijaard et al. (2007), section 5: the matrices at the benchmark parameters (K0 without g).
PUBLISHED = {
    "M": [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]],
    "C1": [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]],
    "K0": [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]],
    "K2": [[0.0, 76.59734589573222], [0.0, 2.65431523794604]],
}

# Table 2 (b, c): the eigenvalues at v = 0, 1, ..., 10 m/s; at v >= 1: castering, capsize and the
# weave pair (real part ± imaginary part).
TABLE2 = {
    0: [-5.53094371765393, -3.13164324790656, 3.13164324790656, 5.53094371765393],
    1: [-7.11008014637442, -3.13423125066578, 3.52696170990070 + 0.80774027519930j],
    2: [-8.67387984831735, -3.07158645641514, 2.68234517512745 + 1.68066296590675j],
    3: [-10.35101467245920, -2.63366137253667, 1.70675605663975 + 2.31582447384325j],
    4: [-12.15861426576450, -1.42944427361326, 0.41325331521125 + 3.07910818603206j],
    5: [-14.07838969279820, -0.32286642900409, -0.77534188219585 + 4.46486771378823j],
    6: [-16.08537123098030, -0.00406690076970, -1.52644486584142 + 5.87673060598709j],
    7: [-18.15788466125262, 0.10268170574766, -2.13875644258362 + 7.19525913329805j],
    8: [-20.27940894394569, 0.14327879765713, -2.69348683581097 + 8.46037971396931j],
    9: [-22.43788559040858, 0.15790184030917, -3.21675402252485 + 9.69377351531791j],
    10: [-24.62459635017404, 0.16105338653172, -3.72016840437287 + 10.90681139476287j],
}

# Table 2 (a): the weave and capsize speeds bounding the self-stable range [m/s].
WEAVE, CAPSIZE = 4.29238253634111, 6.02426201538837


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
