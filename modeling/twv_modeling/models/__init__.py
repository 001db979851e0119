"""The shipped models: the three vehicles and the bicycle (multibody) and the explicit-ODE
reference systems."""

from __future__ import annotations

from pathlib import Path

EXPLICIT_DIR = Path(__file__).parent
VEHICLES = ("vehicle8", "vehicle7", "segway7")
#: Multibody models with their own parameter schema (not the vehicles'), and their files.
OTHER_MULTIBODY = {"whipple": "whipple.toml"}
EXPLICIT = ("lorenz", "henon_heiles")
SHIPPED = VEHICLES + tuple(OTHER_MULTIBODY) + EXPLICIT
