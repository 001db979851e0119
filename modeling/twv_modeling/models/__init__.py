"""The shipped models: the three vehicles (multibody) and the explicit-ODE reference systems."""

from __future__ import annotations

from pathlib import Path

EXPLICIT_DIR = Path(__file__).parent
VEHICLES = ("vehicle8", "vehicle7", "segway7")
EXPLICIT = ("lorenz", "henon_heiles")
SHIPPED = VEHICLES + EXPLICIT
