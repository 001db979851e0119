"""The analyses, one Python function per job of the library's registry, made from it at import:
the same name, the same options (keyword arguments), the library's own defaults in the
signature, its help in the docstring. Nothing here restates a default or a rule: the keywords a
call gives are sent to the library, which lays them over its default settings, checks them and
runs the job. Each returns a result object over exactly what `twv <job> --json` prints."""

from __future__ import annotations

import inspect
import json
import math
import os
from concurrent.futures import Executor
from typing import Any

import numpy as np

from . import _native
from ._gains import Gains
from ._model import Model
from ._native import InputError
from ._results import RESULTS, Result, SweepResult


def _plain(name: str, value: Any) -> Any:
    """A keyword's value as JSON the library reads: arrays as lists, gains as {kp, ki, kd},
    a tune result as its gains, a non-finite float as its text (`inf`; NaN is named by the
    library's validation)."""
    if isinstance(value, Gains):
        return value.to_dict()
    gains = getattr(value, "gains", None)
    if gains is not None and not isinstance(value, dict | list | tuple | str):
        return _plain(name, gains)
    if isinstance(value, np.ndarray):
        return _plain(name, value.tolist())
    if isinstance(value, np.generic):
        return _plain(name, value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, dict):
        return {str(k): _plain(f"{name}.{k}", v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(name, v) for v in value]
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise InputError(f"{name}: {type(value).__name__} is not a value twv takes")


def _ordered(job: dict[str, Any], name: str, value: Any) -> Any:
    """A dict for a repeatable option (`param={"m2": (4, 20, 17), "b": …}`) as its entries in
    the order given (`["m2=4:20:17", …]`): their order is the axes' (a JSON object's is not
    kept)."""
    many = any(o["name"] == name and o["many"] for o in job["options"])
    if many and isinstance(value, dict):
        return [f"{k}={':'.join(str(x) for x in v)}" for k, v in value.items()]
    return value


def _check_model(model: Any) -> Model:
    if not isinstance(model, Model):
        raise InputError(f"model: a twv.Model, not {type(model).__name__}")
    return model


def _docstring(job: dict[str, Any]) -> str:
    lines = [job["summary"] + ".", ""]
    if job["aliases"]:
        lines += [f"Also known as: {', '.join(job['aliases'])}.", ""]
    lines.append("Keyword arguments (the library's defaults):")
    for o in job["options"]:
        unit = f" [{o['unit']}]" if o["unit"] else ""
        choices = f" One of {', '.join(o['choices'])}." if o["choices"] else ""
        default = "required" if o["required"] else f"default {o['default']!r}"
        lines.append(f"  {o['name']}{unit}: {o['help']}.{choices} ({default})")
    lines += [
        "",
        "settings: the job's whole settings as a dict (twv.settings(job)); the keywords are laid",
        "over them. out: a folder to write the job's files into, as `twv <job> --out DIR` does.",
        "Raises InputError naming the option it refuses.",
    ]
    return "\n".join(lines)


def _signature(job: dict[str, Any]) -> inspect.Signature:
    P = inspect.Parameter
    params = [P("model", P.POSITIONAL_ONLY)]
    for o in job["options"]:
        if o["required"]:
            params.append(P(o["name"], P.POSITIONAL_OR_KEYWORD))
    # Optional, but may come by position (an option another can now stand in for).
    for o in job["options"]:
        if o["positional"] and not o["required"]:
            params.append(P(o["name"], P.POSITIONAL_OR_KEYWORD, default=o["default"]))
    for o in job["options"]:
        if not o["required"] and not o["positional"]:
            params.append(P(o["name"], P.KEYWORD_ONLY, default=o["default"]))
    params.append(P("settings", P.KEYWORD_ONLY, default=None))
    params.append(P("out", P.KEYWORD_ONLY, default=None))
    return inspect.Signature(params)


def _given(job: dict[str, Any], signature: inspect.Signature, args, kwargs) -> dict[str, Any]:
    aliases = {a: o["name"] for o in job["options"] for a in o["aliases"]}
    kwargs = {aliases.get(k, k): v for k, v in kwargs.items()}
    try:
        bound = signature.bind(*args, **kwargs)
    except TypeError as e:
        raise InputError(f"{job['name']}: {e}") from None
    return bound.arguments


def _make(job: dict[str, Any]):
    name = job["name"]
    signature = _signature(job)

    def run(*args, **kwargs):
        given = _given(job, signature, args, kwargs)
        model = _check_model(given.pop("model"))
        settings = given.pop("settings", None)
        out = given.pop("out", None)
        options = {k: _plain(k, _ordered(job, k, v)) for k, v in given.items()}
        options_text = json.dumps(options)
        settings_text = None if settings is None else json.dumps(_plain("settings", settings))
        raw, csv, summary, negative = _native.run_options(
            name, model._native, options_text, settings_text, None if out is None else str(out)
        )
        if name == "sweep":
            resolved = json.loads(_native.resolve_options(name, options_text, settings_text))
            return SweepResult(json.loads(raw), csv, summary, negative, model, settings=resolved)
        return RESULTS.get(name, Result)(json.loads(raw), csv, summary, negative, model)

    run.__name__ = run.__qualname__ = name
    run.__doc__ = _docstring(job)
    run.__signature__ = signature
    run.__module__ = "twv"
    return run


JOBS: dict[str, dict[str, Any]] = {j["name"]: j for j in json.loads(_native.jobs())}
"""Every job of the library's registry: name, aliases, summary, options with their defaults."""

FUNCTIONS = {name: _make(job) for name, job in JOBS.items()}


def _sweep_with_executor(plain):
    """`sweep` that also takes `executor` (a concurrent.futures pool, a dask.distributed
    Client) and `shards`: its shards then run there and are joined in index order."""

    def sweep(*args, executor: Executor | None = None, shards: int | None = None, **kwargs):
        if executor is None:
            return plain(*args, **kwargs)
        model, *rest = args
        if rest:
            raise InputError("sweep: the options are keywords")
        return sweep_on(executor, model, shards=shards, **kwargs)

    P = inspect.Parameter
    params = list(plain.__signature__.parameters.values())
    params[-1:-1] = [
        P("executor", P.KEYWORD_ONLY, default=None),
        P("shards", P.KEYWORD_ONLY, default=None),
    ]
    sweep.__signature__ = plain.__signature__.replace(parameters=params)
    sweep.__doc__ = plain.__doc__ + "\n" + (_sweep_with_executor.__doc__ or "")
    sweep.__name__ = sweep.__qualname__ = "sweep"
    sweep.__module__ = "twv"
    return sweep


FUNCTIONS["sweep"] = _sweep_with_executor(FUNCTIONS["sweep"])


def settings(job: str, **options) -> dict[str, Any]:
    """The settings `job` runs with: the library's defaults with `options` laid over them,
    checked (nothing runs)."""
    job = job.replace("-", "_")
    for name, j in JOBS.items():
        if job == name or job in j["aliases"]:
            break
    else:
        raise InputError(f"job: unknown `{job}`; the jobs: {', '.join(JOBS)}")
    plain = {k: _plain(k, v) for k, v in options.items()}
    return json.loads(_native.resolve_options(name, json.dumps(plain)))


def default_settings(job: str) -> dict[str, Any]:
    """The library's default settings of `job` (the same as `settings(job)`)."""
    return json.loads(_native.default_settings(job))


def sweep_on(executor: Executor, model: Model, *, shards: int | None = None, **options):
    """`twv.sweep` with its shards run on `executor` (a concurrent.futures pool, a
    dask.distributed Client) and joined in index order."""
    _check_model(model)
    resolved = settings("sweep", **options)
    text = json.dumps(resolved)
    total = _native.sweep_len(model._native, text)
    n = shards or 4 * getattr(executor, "_max_workers", 2)
    bounds = [total * i // n for i in range(n + 1)]
    futures = [
        executor.submit(_sweep_shard, model, text, lo, hi)
        for lo, hi in zip(bounds, bounds[1:], strict=False)
        if hi > lo
    ]
    points = [p for f in futures for p in json.loads(f.result())]
    return SweepResult(points, None, "", None, model, settings=resolved)


def _sweep_shard(model: Model, settings: str, start: int, stop: int) -> str:
    """One shard of a sweep, in whatever process the executor chose."""
    return _native.sweep_range(model._native, settings, start, stop)


def build_info() -> dict[str, Any]:
    """Which build of twv this is: version, commit, profile (release or debug), architecture,
    the kernels' instruction set and whether the JIT is in (the same as `twv --version`)."""
    return json.loads(_native.build_info())


def report(out, *, params=None, quick: bool = False) -> Result:
    """The study's report into the folder `out` (index.html, figures, data, results.json), from
    the bundled vehicle or a parameter file; `passed` says whether every check held."""
    import os

    raw = _native.report(
        os.fspath(out), params=None if params is None else os.fspath(params), quick=quick
    )
    return Result(json.loads(raw), None, "", None, None)
