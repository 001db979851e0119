"""The modeling command line: derive, check, and clear one-line errors for bad input."""

import subprocess
import sys
import textwrap
from pathlib import Path

from twv_modeling.registry import REPO_ROOT


def run(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "twv_modeling", *args], capture_output=True, text=True, cwd=cwd
    )


USER_MODEL = textwrap.dedent("""
    from twv_modeling.explicit import ExplicitModel
    from twv_modeling.params import Param

    def model():
        m = ExplicitModel("oscillator", states=[("q", "m"), ("v", "m/s")],
                          inputs=[("force", "N")],
                          params=[Param("k", "N/m", default=4.0), Param("mass", "kg", "mass",
                                  default=1.0)])
        q, v = m.x_parts
        (force,) = m.u_parts
        k, mass = m.p_parts
        m.rhs = [v, (force - k * q) / mass]
        return m
""")


def test_derive_user_file_and_model(tmp_path: Path):
    src = tmp_path / "osc.py"
    src.write_text(USER_MODEL)
    out = tmp_path / "osc.json"
    r = run("derive", "--file", str(src), "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert '"model": "oscillator"' in out.read_text()
    out2 = tmp_path / "lorenz.json"
    assert run("derive", "--model", "lorenz", "--out", str(out2)).returncode == 0
    assert out2.read_bytes() == (REPO_ROOT / "generated/ir/lorenz.json").read_bytes()


def test_check_names_stale_files(tmp_path: Path):
    ir_dir = tmp_path / "ir"
    ir_dir.mkdir()
    for f in (REPO_ROOT / "generated/ir").glob("*.json"):
        (ir_dir / f.name).write_bytes(f.read_bytes())
    assert run("check", "--ir-dir", str(ir_dir)).returncode == 0
    stale = ir_dir / "vehicle7.json"
    stale.write_text(stale.read_text().replace('"format"', ' "format"', 1))
    r = run("check", "--ir-dir", str(ir_dir))
    assert r.returncode == 1 and "vehicle7.json" in r.stderr and "lorenz" not in r.stderr


def _one_line_error(r):
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("twv_modeling: error:"), r.stderr
    assert "Traceback" not in r.stderr
    return lines[0]


def test_unknown_model_is_a_clear_error(tmp_path: Path):
    r = run("derive", "--model", "vehicle9", "--out", str(tmp_path / "x.json"))
    assert r.returncode == 2 and "vehicle9" in r.stderr and "Traceback" not in r.stderr


def test_model_file_with_an_error(tmp_path: Path):
    bad = tmp_path / "bad.py"
    bad.write_text(
        USER_MODEL.replace("m.rhs = [v, (force - k * q) / mass]", "m.rhs = [v, undefined]")
    )
    out = tmp_path / "bad.json"
    msg = _one_line_error(run("derive", "--file", str(bad), "--out", str(out)))
    assert "bad.py" in msg and "undefined" in msg
    assert not out.exists()
    missing = _one_line_error(run("derive", "--file", str(tmp_path / "nope.py"), "--out", str(out)))
    assert "nope.py" in missing


def test_wrong_rhs_length(tmp_path: Path):
    bad = tmp_path / "short.py"
    bad.write_text(USER_MODEL.replace("m.rhs = [v, (force - k * q) / mass]", "m.rhs = [v]"))
    msg = _one_line_error(run("derive", "--file", str(bad), "--out", str(tmp_path / "o.json")))
    assert "rhs" in msg


def test_unwritable_output_leaves_no_file(tmp_path: Path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        out = locked / "lorenz.json"
        r = run("derive", "--model", "lorenz", "--out", str(out))
        if r.returncode == 0:  # running as root ignores permissions: use a missing folder too
            out.unlink()
        missing = tmp_path / "no" / "such" / "dir" / "lorenz.json"
        msg = _one_line_error(run("derive", "--model", "lorenz", "--out", str(missing)))
        assert str(missing) in msg
        assert list(locked.iterdir()) == []
    finally:
        locked.chmod(0o700)


def test_test_data_ir_is_what_its_source_derives(tmp_path: Path):
    """tests/data/ring11.json (used by the Rust tests) is fresh: derived again, the same bytes."""
    data = REPO_ROOT / "tests" / "data"
    out = tmp_path / "ring11.json"
    r = run("derive", "--file", str(data / "ring11.py"), "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert out.read_bytes() == (data / "ring11.json").read_bytes()
