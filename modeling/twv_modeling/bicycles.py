"""Measured bicycles as twv parameter files: the benchmark parameter sets that the
`bicycleparameters` package (J. K. Moore's measurements of real bicycles, pinned in
modeling/requirements.txt) distributes with their uncertainties, converted to the Whipple
model's parameters (`vehicles/bicycles/<name>.toml`, one per bicycle).

bicycleparameters does the conversion from the raw measurements (pendulum periods, geometry) to
the 25 benchmark parameters of Meijaard et al. (2007); twv's Whipple model takes exactly those
parameters, so what is left here is the naming (`lam` is `lambda`, `IBxx` is `I_Bxx`, ...) and
writing each value with its standard deviation: the file's `[uncertainty]` table, which twv reads
for Monte Carlo runs and ignores otherwise.

    python -m twv_modeling bicycles           # write vehicles/bicycles/*.toml
    python -m twv_modeling bicycles --check   # exit 1 naming the files that differ
"""

from __future__ import annotations

import math
from pathlib import Path

#: The folder the files are written to.
OUT_DIR = Path(__file__).resolve().parents[2] / "vehicles" / "bicycles"

#: bicycleparameters' benchmark names -> the Whipple model's (vehicles/whipple.toml).
NAMES = {
    "w": "w",
    "c": "c",
    "lam": "lambda",
    "g": "g",
    "rR": "r_R",
    "mR": "m_R",
    "IRxx": "I_Rxx",
    "IRyy": "I_Ryy",
    "xB": "x_B",
    "zB": "z_B",
    "mB": "m_B",
    "IBxx": "I_Bxx",
    "IByy": "I_Byy",
    "IBzz": "I_Bzz",
    "IBxz": "I_Bxz",
    "xH": "x_H",
    "zH": "z_H",
    "mH": "m_H",
    "IHxx": "I_Hxx",
    "IHyy": "I_Hyy",
    "IHzz": "I_Hzz",
    "IHxz": "I_Hxz",
    "rF": "r_F",
    "mF": "m_F",
    "IFxx": "I_Fxx",
    "IFyy": "I_Fyy",
}

#: Units of each twv parameter.
UNITS = {
    **dict.fromkeys(["w", "c", "r_R", "x_B", "z_B", "x_H", "z_H", "r_F"], "m"),
    "lambda": "rad",
    "g": "m/s^2",
    **dict.fromkeys(["m_R", "m_B", "m_H", "m_F"], "kg"),
}

#: Where the values come from: the benchmark's are published; every other set of the data set
#: was measured (J. K. Moore, "Human control of a bicycle", PhD thesis, UC Davis, 2012, and the
#: package's documentation), bicycle only, without a rider.
PUBLISHED = {"Benchmark": "the benchmark bicycle of Meijaard et al. (2007), Table 1 (exact)"}


def describe(name: str) -> str:
    """One line on where bicycle `name`'s values come from."""
    return PUBLISHED.get(
        name,
        f"the bicycle '{name}' of the bicycleparameters data set, measured by J. K. Moore and "
        "colleagues (UC Davis), without a rider",
    )


def data_dir() -> Path:
    """The data set bicycleparameters ships (bicycles/<Name>/Parameters/<Name>Benchmark.txt)."""
    import bicycleparameters

    return Path(bicycleparameters.__file__).resolve().parent / "app-data"


def measured(name: str) -> dict[str, tuple[float, float]]:
    """(value, standard deviation) of each twv parameter of bicycle `name`, as bicycleparameters
    reads them from its data set."""
    import contextlib
    import io
    import warnings

    import bicycleparameters

    # It prints what it loads, and `uncertainties` warns about its exact values (std 0).
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        bike = bicycleparameters.Bicycle(name, pathToData=str(data_dir()))
    benchmark = bike.parameters["Benchmark"]
    out = {}
    for theirs, ours in NAMES.items():
        value = benchmark[theirs]
        nominal = float(getattr(value, "nominal_value", value))
        std = float(getattr(value, "std_dev", 0.0))
        out[ours] = (nominal, std)
    return out


def available() -> list[str]:
    """The bicycles of the data set that have benchmark parameters, sorted."""
    folder = data_dir() / "bicycles"
    return sorted(
        p.name for p in folder.iterdir() if (p / "Parameters" / f"{p.name}Benchmark.txt").exists()
    )


def _number(x: float) -> str:
    """Shortest text that reads back as the same double."""
    text = repr(float(x))
    return text if math.isfinite(x) else "nan"


def toml_text(name: str) -> str:
    """The parameter file of bicycle `name`."""
    import bicycleparameters

    values = measured(name)
    what = describe(name)
    version = bicycleparameters.__version__
    lines = [
        f"# {name}: {what}.",
        f"# Converted by `python -m twv_modeling bicycles` from bicycleparameters {version}",
        f"# (bicycles/{name}/Parameters/{name}Benchmark.txt of its data set): the 25 benchmark",
        "# parameters of Meijaard et al. (2007), named as in vehicles/whipple.toml; SI units,",
        "# x forward, z down, origin at the rear contact point. [uncertainty]: one standard",
        "# deviation of each value, as the data set gives it (twv reads it for Monte Carlo runs;",
        "# a value without one is exact).",
        "",
    ]
    for key, (value, _) in values.items():
        unit = UNITS.get(key, "kg m^2")
        lines.append(f"{key} = {_number(value)}  # [{unit}]")
    lines += ["", "[uncertainty]"]
    for key, (_, std) in values.items():
        if std > 0:
            lines.append(f"{key} = {_number(std)}")
    return "\n".join(lines) + "\n"


def write_all(out_dir: Path = OUT_DIR) -> list[Path]:
    """Writes every bicycle's file; returns their paths."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for name in available():
        path = out_dir / f"{name.lower()}.toml"
        path.write_text(toml_text(name))
        written.append(path)
    return written


def stale(out_dir: Path = OUT_DIR) -> list[str]:
    """The files that differ from what the conversion writes today (or are missing)."""
    bad = []
    for name in available():
        path = out_dir / f"{name.lower()}.toml"
        if not path.exists() or path.read_text() != toml_text(name):
            bad.append(str(path))
    return bad
