"""NumPy inputs checked at the door: float64, C order, the right shape, finite; errors name the
argument."""

from __future__ import annotations

import numpy as np

from ._native import InputError


def rows(name: str, value, width: int) -> tuple[np.ndarray, bool]:
    """`value` as an (n, width) float64 C-contiguous array, and whether it was one row (1-D)."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise InputError(f"{name}: not an array of numbers ({err})") from None
    if a.ndim == 1:
        single, a = True, a.reshape(1, -1)
    elif a.ndim == 2:
        single = False
    else:
        raise InputError(f"{name}: {a.ndim}-D array; want shape ({width},) or (n, {width})")
    if a.shape[1] != width:
        raise InputError(f"{name}: {a.shape[1]} columns; want {width}")
    return np.ascontiguousarray(a), single


def vector(name: str, value, width: int | None = None) -> list[float]:
    """`value` as a list of finite floats (of length `width` if given)."""
    try:
        a = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError) as err:
        raise InputError(f"{name}: not a vector of numbers ({err})") from None
    if width is not None and a.size != width:
        raise InputError(f"{name}: {a.size} numbers; want {width}")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise InputError(f"{name}[{bad[0]}] = {a[bad[0]]} is not finite")
    return [float(v) for v in a]
