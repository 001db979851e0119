"""The quickstart notebook runs top to bottom (nbclient, a real Jupyter kernel), so it cannot
rot; its figures are written and its printed checks hold."""

from __future__ import annotations

import shutil

import nbformat
from conftest import REPO
from nbclient import NotebookClient


def test_quickstart_runs(tmp_path):
    notebook = tmp_path / "quickstart.ipynb"
    shutil.copy(REPO / "examples" / "quickstart.ipynb", notebook)
    nb = nbformat.read(notebook, as_version=4)
    NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    text = "\n".join(
        o.get("text", "") for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
    )
    assert "bit-identical to the compiled model: True" in text
    assert "met" in text and "tuned PD: recovered" in text
    for name in ("spectrum", "tilt", "map"):
        assert (tmp_path / f"quickstart-{name}.png").stat().st_size > 10_000
