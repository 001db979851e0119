"""The linearised Whipple bicycle in closed form: the benchmark of Meijaard, Papadopoulos, Ruina &
Schwab (2007), Proc. R. Soc. A 463: 1955-1982, their Appendix A.

    M q'' + v C1 q' + (g K0 + v^2 K2) q = f,    q = (roll phi, steer delta),  f = (T_phi, T_delta)

M, C1, K0 and K2 follow from the 25 parameters of their Table 1 (`vehicles/whipple.toml`) by the
formulas below, written from the paper. This is an external reference for twv's own derivation
of the bicycle (issue: any two-wheeled vehicle from bodies, joints and rolling contacts): the
linearisation of the derived nonlinear equations about upright straight running at speed v must
equal these matrices, and its eigenvalues the paper's Table 2.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

#: The benchmark's parameter file.
DEFAULT_FILE = Path(__file__).resolve().parents[2] / "vehicles" / "whipple.toml"

#: Every parameter of Table 1, in the file's names.
NAMES = (
    *("w", "c", "lambda", "g"),
    *("r_R", "m_R", "I_Rxx", "I_Ryy"),
    *("x_B", "z_B", "m_B", "I_Bxx", "I_Byy", "I_Bzz", "I_Bxz"),
    *("x_H", "z_H", "m_H", "I_Hxx", "I_Hyy", "I_Hzz", "I_Hxz"),
    *("r_F", "m_F", "I_Fxx", "I_Fyy"),
)


@dataclass(frozen=True)
class BenchmarkMatrices:
    """M, C1, K0, K2 of the linearised bicycle (2x2 each, rows/columns roll, steer)."""

    M: np.ndarray
    C1: np.ndarray
    K0: np.ndarray
    K2: np.ndarray
    g: float

    def state_matrix(self, v: float) -> np.ndarray:
        """A of x' = A x for x = (phi, delta, phi', delta') at speed v (no input)."""
        minv = np.linalg.inv(self.M)
        a = np.zeros((4, 4))
        a[:2, 2:] = np.eye(2)
        a[2:, :2] = -minv @ (self.g * self.K0 + v * v * self.K2)
        a[2:, 2:] = -minv @ (v * self.C1)
        return a

    def eigenvalues(self, v: float) -> np.ndarray:
        """The four eigenvalues at speed v, sorted by real part, then imaginary part."""
        ev = np.linalg.eigvals(self.state_matrix(v))
        return ev[np.lexsort((ev.imag, ev.real))]

    def spectral_abscissa(self, v: float) -> float:
        """The largest real part at speed v: < 0 means self-stable."""
        return float(np.max(self.eigenvalues(v).real))

    def stable_speed_range(self, lo: float = 0.0, hi: float = 10.0, step: float = 0.01):
        """(weave speed, capsize speed): where the spectral abscissa changes sign, each root
        bracketed on a grid of `step` and refined by Brent's method to 1e-14 m/s; None where the
        bicycle is nowhere self-stable in [lo, hi]."""
        speeds = np.arange(lo, hi + step / 2, step)
        sa = np.array([self.spectral_abscissa(v) for v in speeds])
        crossings = [
            brentq(self.spectral_abscissa, speeds[i], speeds[i + 1], xtol=1e-14, rtol=1e-15)
            for i in range(len(speeds) - 1)
            if sa[i] > 0 >= sa[i + 1] or sa[i] <= 0 < sa[i + 1]
        ]
        if len(crossings) < 2:
            return None
        return crossings[0], crossings[1]


def read_parameters(path: str | Path = DEFAULT_FILE) -> dict[str, float]:
    """Table 1 from a parameter file; every name must be there, as a finite number. An
    `[uncertainty]` table (standard deviations, vehicles/bicycles/) is not a value."""
    path = Path(path)
    table = tomllib.loads(path.read_text(encoding="utf-8"))
    table.pop("uncertainty", None)
    missing = [n for n in NAMES if n not in table]
    if missing:
        raise ValueError(f"{path}: missing {', '.join(missing)}")
    unknown = sorted(set(table) - set(NAMES))
    if unknown:
        raise ValueError(f"{path}: unknown {', '.join(unknown)}")
    values = {}
    for n in NAMES:
        v = table[n]
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ValueError(f"{path}: {n} = {v!r} is not a finite number")
        values[n] = float(v)
    return values


def benchmark_matrices(p: dict[str, float]) -> BenchmarkMatrices:
    """Meijaard et al. (2007), Appendix A: the matrices from the parameters."""
    w, c, lam, g = p["w"], p["c"], p["lambda"], p["g"]
    r_r, m_r, i_rxx, i_ryy = p["r_R"], p["m_R"], p["I_Rxx"], p["I_Ryy"]
    x_b, z_b, m_b = p["x_B"], p["z_B"], p["m_B"]
    i_bxx, i_bzz, i_bxz = p["I_Bxx"], p["I_Bzz"], p["I_Bxz"]
    x_h, z_h, m_h = p["x_H"], p["z_H"], p["m_H"]
    i_hxx, i_hzz, i_hxz = p["I_Hxx"], p["I_Hzz"], p["I_Hxz"]
    r_f, m_f, i_fxx, i_fyy = p["r_F"], p["m_F"], p["I_Fxx"], p["I_Fyy"]
    sl, cl = math.sin(lam), math.cos(lam)

    # The whole bicycle as one rigid body, about the rear contact point (A.1-A.5).
    m_t = m_r + m_b + m_h + m_f
    x_t = (x_b * m_b + x_h * m_h + w * m_f) / m_t
    z_t = (-r_r * m_r + z_b * m_b + z_h * m_h - r_f * m_f) / m_t
    i_txx = i_rxx + i_bxx + i_hxx + i_fxx
    i_txx += m_r * r_r**2 + m_b * z_b**2 + m_h * z_h**2 + m_f * r_f**2
    i_txz = i_bxz + i_hxz - m_b * x_b * z_b - m_h * x_h * z_h + m_f * w * r_f
    i_rzz, i_fzz = i_rxx, i_fxx
    i_tzz = i_rzz + i_bzz + i_hzz + i_fzz + m_b * x_b**2 + m_h * x_h**2 + m_f * w**2

    # The front assembly A = H + F (A.6-A.12), its inertia about the steer axis.
    m_a = m_h + m_f
    x_a = (x_h * m_h + w * m_f) / m_a
    z_a = (z_h * m_h - r_f * m_f) / m_a
    i_axx = i_hxx + i_fxx + m_h * (z_h - z_a) ** 2 + m_f * (r_f + z_a) ** 2
    i_axz = i_hxz - m_h * (x_h - x_a) * (z_h - z_a) + m_f * (w - x_a) * (r_f + z_a)
    i_azz = i_hzz + i_fzz + m_h * (x_h - x_a) ** 2 + m_f * (w - x_a) ** 2
    u_a = (x_a - w - c) * cl - z_a * sl
    i_all = m_a * u_a**2 + i_axx * sl**2 + 2 * i_axz * sl * cl + i_azz * cl**2
    i_alx = -m_a * u_a * z_a + i_axx * sl + i_axz * cl
    i_alz = m_a * u_a * x_a + i_axz * sl + i_azz * cl

    # Trail ratio and the wheels' gyrostatic coefficients (A.13-A.16).
    mu = c / w * cl
    s_r, s_f = i_ryy / r_r, i_fyy / r_f
    s_t = s_r + s_f
    s_a = m_a * u_a + mu * m_t * x_t

    m_pd = i_alx + mu * i_txz
    m = np.array([[i_txx, m_pd], [m_pd, i_all + 2 * mu * i_alz + mu**2 * i_tzz]])
    k0 = np.array([[m_t * z_t, -s_a], [-s_a, -s_a * sl]])
    k2 = np.array([[0.0, (s_t - m_t * z_t) * cl / w], [0.0, (s_a + s_f * sl) * cl / w]])
    c1 = np.array(
        [
            [0.0, mu * s_t + s_f * cl + i_txz * cl / w - mu * m_t * z_t],
            [-(mu * s_t + s_f * cl), i_alz * cl / w + mu * (s_a + i_tzz * cl / w)],
        ]
    )
    return BenchmarkMatrices(M=m, C1=c1, K0=k0, K2=k2, g=g)
