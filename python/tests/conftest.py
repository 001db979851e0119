"""Shared fixtures: the repository, the `twv` binary the Rust tests built, models."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

import twv

REPO = Path(__file__).resolve().parents[2]


def twv_binary() -> Path:
    """The CLI to compare with: TWV_BIN, else the debug build of the test command, else the
    release build of the main command."""
    if "TWV_BIN" in os.environ:
        return Path(os.environ["TWV_BIN"])
    for profile in ("debug", "release"):
        path = REPO / "target" / profile / "twv"
        if path.is_file():
            return path
    pytest.fail("no twv binary: run `cargo build -p twv-cli` (the test command does)")


def cli_json(*args: str, cwd: Path | None = None, flag: bool = True) -> dict:
    """`twv ARGS --json` parsed (`flag=False`: a command that always prints JSON); a failure
    shows the CLI's message."""
    out = subprocess.run(
        [str(twv_binary()), *args, *(["--json", "--quiet"] if flag else [])],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )
    assert out.returncode in (0, 1, 3), out.stderr
    return json.loads(out.stdout)


def cli_shard(out: Path, *args: str) -> dict:
    """`twv sweep ARGS --out OUT --quiet` run as one shard, its shard file parsed."""
    subprocess.run(
        [str(twv_binary()), "sweep", *args, "--out", str(out), "--quiet"],
        check=True,
        timeout=300,
    )
    return json.loads((out / "shard-0-of-1.json").read_text())


@pytest.fixture(scope="session")
def vehicle8() -> twv.Model:
    return twv.Model("vehicle8")
