"""`twv.Gains`: the pitch loop's PID gains, by name only (a tuple's order would be a guess)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, kw_only=True)
class Gains:
    """F = kp·e + ki·∫e + kd·Φ̇ [N/rad, N/(rad s), N s/rad]; ki = 0 is a PD law.

    Accepted wherever gains are (`gains=`), as is a dict {"kp": …, "kd": …} or a tune result.
    """

    kp: float
    kd: float
    ki: float = 0.0

    def to_dict(self) -> dict[str, float]:
        return {"kp": float(self.kp), "ki": float(self.ki), "kd": float(self.kd)}
