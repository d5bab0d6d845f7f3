"""Sweep files: what a sweep varies, checked, and the runs it stands for.

A sweep file (TOML) names a base scenario and the scenario fields that vary, each by its
dotted path::

    scenario = "knee_flexion.toml"     # relative to this file
    method = "latin_hypercube"         # "grid", "random" or "latin_hypercube"
    runs = 16                          # random and latin_hypercube only
    seed = 7                           # default 0
    target_knee_deg = 60.0             # optional: each run's time_to_target_s
    frames = false                     # keep each run's VTU/GLB frames (default false)

    [parameters]
    "body.mass_kg" = { min = 50.0, max = 90.0 }          # a range
    "tissue.iterations" = { min = 2, max = 8 }           # integers when both are
    "simulation.tendon" = ["rigid", "compliant"]         # a list of values
    "muscle.hamstrings.max_force_scale" = { min = 0.8, max = 1.2, steps = 3 }  # grid

A grid takes every combination (a range needs ``steps`` there); random draws each run's
values independently; a Latin hypercube gives each parameter's range ``runs`` equal strata
and puts one run in each. Lists are drawn from (or stratified by index) by the last two.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ._myoslice import __version__, check_scenario
from ._toml import dumps, tomllib
from .errors import InvalidInputError

__all__ = ["METHODS", "Range", "Run", "SweepPlan", "load_sweep", "plan_sweep"]

#: Ways of choosing the runs.
METHODS = ("grid", "random", "latin_hypercube")

_KEYS = {"scenario", "method", "runs", "seed", "target_knee_deg", "frames", "parameters"}


@dataclass(frozen=True)
class Range:
    """A parameter's range: ``min`` to ``max`` (integers when both are), ``steps``
    values for a grid."""

    min: float
    max: float
    integer: bool
    steps: int | None

    def grid(self) -> list[Any]:
        """``steps`` evenly spaced values from min to max."""
        n = self.steps or 0
        values = np.linspace(self.min, self.max, n) if n > 1 else np.array([self.min])
        return [int(round(v)) if self.integer else float(v) for v in values]

    def at(self, u: float) -> Any:
        """The value a fraction ``u`` in [0, 1) of the way along the range."""
        if self.integer:
            lo, hi = int(self.min), int(self.max)
            return min(hi, lo + int(math.floor(u * (hi - lo + 1))))
        return float(self.min + u * (self.max - self.min))


@dataclass(frozen=True)
class Run:
    """One run of a sweep: its index, folder name and parameter values."""

    index: int
    id: str
    params: dict[str, Any]


@dataclass(frozen=True)
class SweepPlan:
    """A checked sweep file and the runs it stands for."""

    path: Path
    scenario: Path
    scenario_text: str
    method: str
    seed: int
    target_knee_deg: float | None
    frames: bool
    parameters: dict[str, Range | list[Any]]
    runs: list[Run]

    def run_toml(self, run: Run) -> str:
        """The scenario text of one run: the base scenario with the run's values."""
        base = tomllib.loads(self.scenario_text)
        for key, value in run.params.items():
            _set_dotted(base, key, value)
        if not self.frames:
            base.setdefault("output", {}).update({"vtu": False, "glb": False})
        return dumps(base)

    def fingerprint(self) -> str:
        """A digest of what the runs compute: the version of myoslice, the base scenario
        and every run's values (a folder holding another sweep's runs is refused)."""
        doc = {
            "version": __version__,
            "scenario": self.scenario_text,
            "frames": self.frames,
            "target_knee_deg": self.target_knee_deg,
            "runs": [[r.id, r.params] for r in self.runs],
        }
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()


def _err(path: Path, msg: str) -> InvalidInputError:
    return InvalidInputError(f"{path}: {msg}")


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _parameter(path: Path, key: str, spec: Any, method: str) -> Range | list[Any]:
    where = f"parameters.\"{key}\""
    if isinstance(spec, list):
        if not spec:
            raise _err(path, f"{where}: an empty list of values")
        kinds = {"number" if _number(v) else type(v).__name__ for v in spec}
        if len(kinds) > 1 or not kinds <= {"number", "str", "bool"}:
            raise _err(
                path,
                f"{where} = {spec!r}: expected values of one kind (numbers, strings or "
                "booleans)",
            )
        return spec
    if not isinstance(spec, dict):
        raise _err(
            path,
            f"{where} = {spec!r}: expected a list of values or a range {{ min = ..., max = ... }}",
        )
    unknown = set(spec) - {"min", "max", "steps"}
    if unknown:
        raise _err(path, f"{where}: unknown key(s) {sorted(unknown)}; a range has min, max, steps")
    if "min" not in spec or "max" not in spec:
        raise _err(path, f"{where}: a range needs both min and max")
    lo, hi = spec["min"], spec["max"]
    for name, v in (("min", lo), ("max", hi)):
        if not _number(v) or not math.isfinite(v):
            raise _err(path, f"{where}.{name} = {v!r}: expected a finite number")
    if lo > hi:
        raise _err(path, f"{where}: min = {lo} is greater than max = {hi}")
    steps = spec.get("steps")
    if steps is not None and (not isinstance(steps, int) or isinstance(steps, bool) or steps < 1):
        raise _err(path, f"{where}.steps = {steps!r}: expected a whole number >= 1")
    if method == "grid" and steps is None:
        raise _err(path, f"{where}: a grid needs the range's steps (how many values)")
    integer = isinstance(lo, int) and isinstance(hi, int)
    if integer and steps is not None and steps > hi - lo + 1:
        raise _err(
            path, f"{where}: {steps} steps from {lo} to {hi} would repeat whole numbers"
        )
    return Range(float(lo), float(hi), integer, steps)


def _values(plan_params: dict[str, Range | list[Any]], method: str, runs: int | None,
            seed: int) -> list[dict[str, Any]]:
    keys = list(plan_params)
    if method == "grid":
        axes = [p if isinstance(p, list) else p.grid() for p in plan_params.values()]
        return [dict(zip(keys, combo)) for combo in itertools.product(*axes)]
    assert runs is not None
    rng = np.random.Generator(np.random.PCG64(seed))
    columns: list[list[Any]] = []
    for p in plan_params.values():
        if method == "random":
            u = rng.random(runs)
        else:  # latin hypercube: one run in each of `runs` strata, in shuffled order
            u = (rng.permutation(runs) + rng.random(runs)) / runs
        if isinstance(p, list):
            columns.append([p[min(len(p) - 1, int(x * len(p)))] for x in u])
        else:
            columns.append([p.at(float(x)) for x in u])
    return [dict(zip(keys, row)) for row in zip(*columns)] if columns else [{}] * runs


def load_sweep(path: str | Path) -> SweepPlan:
    """Reads and checks a sweep file, and every run's scenario (each field must exist and
    hold a valid value), before anything runs. Raises
    :class:`~myoslice.errors.InvalidInputError` naming what is wrong."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise _err(path, "sweep file not found") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise _err(path, f"not a readable TOML file: {e}") from None
    return plan_sweep(path, doc)


def plan_sweep(path: Path, doc: dict[str, Any]) -> SweepPlan:
    """A sweep file's content already read (``path`` places the scenario and names it in
    errors), checked as :func:`load_sweep` checks it."""
    unknown = set(doc) - _KEYS
    if unknown:
        raise _err(path, f"unknown key(s) {sorted(unknown)}; a sweep file has {sorted(_KEYS)}")
    if not isinstance(doc.get("scenario"), str):
        raise _err(path, "scenario = \"...\" (the base scenario file) is required")
    scenario = (path.parent / doc["scenario"]).resolve()
    try:
        scenario_text = scenario.read_text(encoding="utf-8")
        base = tomllib.loads(scenario_text)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise _err(path, f"scenario {scenario}: {e}") from None
    method = doc.get("method", "grid")
    if method not in METHODS:
        raise _err(path, f"method = {method!r}: expected one of {', '.join(METHODS)}")
    seed = doc.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise _err(path, f"seed = {seed!r}: expected a whole number >= 0")
    runs = doc.get("runs")
    if method == "grid":
        if runs is not None:
            raise _err(path, "runs: a grid runs every combination; runs is for random and "
                             "latin_hypercube")
    elif not isinstance(runs, int) or isinstance(runs, bool) or runs < 1:
        raise _err(path, f"runs = {runs!r}: {method} needs how many runs (a whole number >= 1)")
    target = doc.get("target_knee_deg")
    if target is not None and (not _number(target) or not math.isfinite(target)):
        raise _err(path, f"target_knee_deg = {target!r}: expected a number (degrees)")
    frames = doc.get("frames", False)
    if not isinstance(frames, bool):
        raise _err(path, f"frames = {frames!r}: expected true or false")
    raw = doc.get("parameters", {})
    if not isinstance(raw, dict):
        raise _err(path, "[parameters] must be a table of dotted scenario paths")
    params = {k: _parameter(path, k, v, method) for k, v in raw.items()}
    values = _values(params, method, runs, seed)
    plan = SweepPlan(
        path=path,
        scenario=scenario,
        scenario_text=scenario_text,
        method=method,
        seed=seed,
        target_knee_deg=float(target) if target is not None else None,
        frames=frames,
        parameters=params,
        runs=[Run(i, f"run-{i:04d}", v) for i, v in enumerate(values)],
    )
    for key in params:
        _check_key(path, base, key)
    for run in plan.runs:
        try:
            # The first run's model is built too, which checks the muscle and group names
            # (the same in every run); the others are read and their settings checked.
            check_scenario(str(scenario), text=plan.run_toml(run), build=run.index == 0)
        except Exception as e:
            shown = ", ".join(f"{k} = {v!r}" for k, v in run.params.items())
            raise _err(path, f"{run.id} ({shown}) gives no valid scenario: {e}") from None
    return plan


def _check_key(path: Path, base: dict[str, Any], key: str) -> None:
    """Refuses a dotted path that cannot name a scenario value (before the scenario's own
    checks, which name unknown fields)."""
    parts = key.split(".")
    if len(parts) < 2 or any(not p for p in parts):
        raise _err(path, f"parameters.\"{key}\": expected a dotted path such as body.mass_kg")
    node: Any = base
    for p in parts[:-1]:
        node = node.get(p, {}) if isinstance(node, dict) else None
        if node is None or not isinstance(node, dict):
            raise _err(path, f"parameters.\"{key}\": {p} is not a table in the scenario")
    if parts[0] == "excitation":
        raise _err(path, f"parameters.\"{key}\": schedules are lists; vary "
                         "simulation.excitation_scale instead")


def _set_dotted(doc: dict[str, Any], key: str, value: Any) -> None:
    *tables, leaf = key.split(".")
    node = doc
    for t in tables:
        node = node.setdefault(t, {})
    node[leaf] = value
