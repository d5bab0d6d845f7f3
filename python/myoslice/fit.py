"""Fitting muscle parameters to a measured knee trajectory with Ray Tune.

:func:`fit` searches factors on the catalogue's muscle parameters (a scenario's
``muscle.NAME.max_force_scale``, ``optimal_fibre_length_scale``,
``tendon_slack_length_scale``, per muscle or group; any scenario field holding a real
number works, such as ``body.mass_kg``) for
the run whose knee angle best matches a target trajectory, by the root mean square of the
difference at the target's times.

The search refines a grid: each round is one Ray Tune experiment of ``points`` values per
parameter (every combination not run before, in parallel), and the next round's grid
spans one grid step either side of the best, ``2 / (points - 1)`` of the last one. It is
deterministic: the same inputs give the same answer.

A fit file (``python -m myoslice fit FIT.toml --out DIR``) holds the same::

    scenario = "knee_flexion.toml"      # relative to this file
    target = "measured.csv"             # columns time_s, knee_angle_deg (a run's
                                        # timeseries.csv is one)
    rounds = 4                          # default 4
    points = 5                          # default 5

    [parameters]
    "muscle.hamstrings.max_force_scale" = { min = 0.5, max = 2.0 }
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import shutil
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._myoslice import run_scenario
from ._ray import ray_session
from .errors import InvalidInputError
from ._toml import tomllib
from .sweep_plan import Run, SweepPlan, plan_sweep

__all__ = ["FitResult", "fit", "fit_file", "read_trajectory"]


@dataclass
class FitResult:
    """What a fit found: the best values, their error, and each round's best."""

    params: dict[str, float]
    rms_error_deg: float
    trials: int
    rounds: list[dict[str, Any]] = field(default_factory=list)


def read_trajectory(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and knee angles (deg) from a CSV with columns ``time_s`` and
    ``knee_angle_deg`` (others are ignored), times increasing."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        raise InvalidInputError(f"{path}: {e}") from None
    if not rows or "time_s" not in rows[0] or "knee_angle_deg" not in rows[0]:
        raise InvalidInputError(f"{path}: expected a CSV with columns time_s and knee_angle_deg")
    try:
        t = np.array([float(r["time_s"]) for r in rows])
        a = np.array([float(r["knee_angle_deg"]) for r in rows])
    except (TypeError, ValueError) as e:
        raise InvalidInputError(f"{path}: {e}") from None
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
        raise InvalidInputError(f"{path}: a time or angle is not a finite number")
    if np.any(np.diff(t) <= 0):
        raise InvalidInputError(f"{path}: times must increase")
    return t, a


def _rms_error(job: dict[str, Any], values: dict[str, float]) -> float:
    """Runs the scenario with ``values`` and measures it against the target."""
    plan: SweepPlan = job["plan"]
    run = Run(0, "trial", values)
    work = Path(tempfile.mkdtemp(prefix="myoslice-fit-"))
    try:
        run_scenario(str(plan.scenario), str(work), text=plan.run_toml(run), reuse_model=True)
        t, a = read_trajectory(work / "timeseries.csv")
    except Exception:
        return math.inf  # a failed run is the worst fit, not the end of the search
    finally:
        shutil.rmtree(work, ignore_errors=True)
    times, target = job["target"]
    sim = np.interp(times, t, a)
    return float(np.sqrt(np.mean((sim - target) ** 2)))


def _trial(config: dict[str, Any], job: dict[str, Any]) -> None:
    from ray import tune

    values = {k: float(v) for k, v in zip(job["keys"], config["point"])}
    tune.report({"rms_error_deg": _rms_error(job, values)})


def fit(
    scenario: str | Path,
    target: str | Path,
    parameters: dict[str, tuple[float, float]],
    *,
    rounds: int = 4,
    points: int = 5,
    out: str | Path | None = None,
    address: str | None = None,
    workers: int | None = None,
) -> FitResult:
    """Finds the values of ``parameters`` (dotted scenario paths, each with a
    ``(min, max)`` range) whose run of ``scenario`` best matches the knee trajectory in
    the CSV ``target`` (see :func:`read_trajectory`), by a grid refined over ``rounds``
    Ray Tune experiments of ``points`` values per parameter. ``out`` keeps Tune's trials
    and ``fit.json``; ``address``/``workers`` as in :func:`myoslice.sweep.sweep`.

    Example (``python/examples/fit_hamstrings.py`` runs it on a synthetic target)::

        result = myoslice.fit.fit(
            "knee_flexion.toml", "measured.csv",
            {"muscle.hamstrings.max_force_scale": (0.5, 2.0)},
        )
        print(result.params, result.rms_error_deg)
    """
    scenario = Path(scenario).resolve()
    if not parameters:
        raise InvalidInputError("fit: no parameters to fit")
    for name, v, least in (("rounds", rounds, 1), ("points", points, 4)):
        if not isinstance(v, int) or isinstance(v, bool) or v < least:
            # Fewer than 4 points a side would not narrow the grid from round to round.
            raise InvalidInputError(f"fit: {name} = {v!r}: expected a whole number >= {least}")
    bounds: dict[str, tuple[float, float]] = {}
    for k, r in parameters.items():
        try:
            lo, hi = (float(r[0]), float(r[1]))
        except (TypeError, ValueError, IndexError):
            raise InvalidInputError(f"fit: {k} = {r!r}: expected (min, max)") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise InvalidInputError(f"fit: {k} = {r!r}: expected finite min < max")
        bounds[k] = (lo, hi)
    times, angles = read_trajectory(target)
    spec = {k: {"min": lo, "max": hi, "steps": points} for k, (lo, hi) in bounds.items()}
    # Checks every field and value through the sweep file's rules before anything runs.
    plan = plan_sweep(
        scenario.parent / "fit",
        {"scenario": str(scenario), "method": "grid", "parameters": spec},
    )
    duration = tomllib.loads(plan.scenario_text).get("simulation", {}).get("duration_s", 0.0)
    if times[-1] > duration + 1e-9:
        raise InvalidInputError(
            f"{target}: the trajectory lasts {times[-1]} s, the scenario {duration} s"
        )
    keys = list(bounds)
    job = {"plan": plan, "keys": keys, "target": (times, angles)}
    out_dir = Path(out).resolve() if out is not None else None
    box = dict(bounds)
    seen: dict[tuple[float, ...], float] = {}
    best: tuple[float, dict[str, float]] = (math.inf, {})
    history: list[dict[str, Any]] = []
    with ray_session(address, workers) as _:
        from ray import tune

        storage = out_dir or Path(tempfile.mkdtemp(prefix="myoslice-tune-"))
        for round_no in range(rounds):
            # Values to 12 digits, so that a point met again is known as the same.
            grids = {
                key: [float(f"{x:.12g}") for x in np.linspace(lo, hi, points)]
                for key, (lo, hi) in box.items()
            }
            # Points of an earlier round are not run again.
            new = [p for p in itertools.product(*grids.values()) if p not in seen]
            if new:
                tuner = tune.Tuner(
                    tune.with_parameters(_trial, job=job),
                    param_space={"point": tune.grid_search(new)},
                    # Trials reuse their worker processes, and with them the lattice.
                    tune_config=tune.TuneConfig(
                        metric="rms_error_deg", mode="min", reuse_actors=True
                    ),
                    run_config=tune.RunConfig(
                        name=f"round-{round_no}", storage_path=str(storage / "tune"), verbose=0
                    ),
                )
                results = tuner.fit()
                for n in range(len(results)):
                    trial = results[n]
                    if trial.metrics and "rms_error_deg" in trial.metrics and trial.config:
                        point = tuple(float(x) for x in trial.config["point"])
                        seen[point] = float(trial.metrics["rms_error_deg"])
            if not seen:
                break
            # Ties broken by the values, so that the answer is deterministic.
            error, point = min((e, p) for p, e in seen.items())
            best = (error, dict(zip(keys, point)))
            history.append({"round": round_no, "rms_error_deg": error, "params": best[1]})
            box = {}
            for key, (lo, hi) in bounds.items():
                step = (grids[key][-1] - grids[key][0]) / (points - 1)
                c = best[1][key]
                box[key] = (max(lo, c - step), min(hi, c + step))
        if out_dir is None:
            shutil.rmtree(storage, ignore_errors=True)
    trials = len(seen)
    if not math.isfinite(best[0]):
        raise InvalidInputError(f"fit: every run of {scenario} failed")
    result = FitResult(params=best[1], rms_error_deg=best[0], trials=trials, rounds=history)
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "fit.json").write_text(json.dumps(asdict(result), indent=1), encoding="utf-8")
    return result


def fit_file(
    path: str | Path, out: str | Path, *, address: str | None = None, workers: int | None = None
) -> FitResult:
    """Runs the fit a fit file describes (see the module's documentation) into ``out``."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise InvalidInputError(f"{path}: {e}") from None
    unknown = set(doc) - {"scenario", "target", "rounds", "points", "parameters"}
    if unknown:
        raise InvalidInputError(f"{path}: unknown key(s) {sorted(unknown)}")
    for key in ("scenario", "target"):
        if not isinstance(doc.get(key), str):
            raise InvalidInputError(f"{path}: {key} = \"...\" is required")
    raw = doc.get("parameters", {})
    if not isinstance(raw, dict) or not raw:
        raise InvalidInputError(f"{path}: [parameters] must name what to fit")
    params = {}
    for k, v in raw.items():
        if not isinstance(v, dict) or set(v) != {"min", "max"}:
            raise InvalidInputError(f"{path}: parameters.\"{k}\": expected {{ min = ..., max = ... }}")
        params[k] = (v["min"], v["max"])
    return fit(
        path.parent / doc["scenario"],
        path.parent / doc["target"],
        params,
        rounds=doc.get("rounds", 4),
        points=doc.get("points", 5),
        out=out,
        address=address,
        workers=workers,
    )
