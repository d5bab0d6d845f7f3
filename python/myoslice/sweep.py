"""Parameter sweeps: many scenario runs as Ray tasks (or one after another), gathered into
one Parquet table.

``myoslice sweep SWEEP.toml --out DIR`` and :func:`sweep` run every run of a sweep file
(:mod:`myoslice.sweep_plan` describes the file) and write, in ``DIR``:

- ``results.parquet``: a row per run, sorted by run, with its parameters (a column per
  dotted path) and its figures (:data:`FIGURES`), and ``error`` (None, or why it failed);
- ``runs/run-NNNN/summary.json`` (what ``myoslice run`` writes) and ``row.json``;
- ``sweep.json``: the plan, so that the sweep started again into the same folder skips
  the runs already done (and refuses a folder holding another sweep).

Each run is a Ray task on one CPU. With no ``address``, a local Ray is started in the
process on 127.0.0.1 (no cluster needed); ``address`` joins a running cluster (``ray start
--head``), whose nodes need this package installed. A run that fails is recorded with its
error and the others go on; a node lost mid-run has its runs retried on the others.
The runs give the same bits on Ray as one after another (``serial=True``), except the
columns of :data:`TIMING_COLUMNS`, which measure this machine.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ._myoslice import run_scenario
from ._ray import RUN_ENV, ray_session
from .fit import read_trajectory
from .errors import InvalidInputError
from .sweep_plan import Run, SweepPlan, load_sweep

__all__ = ["FIGURES", "TIMING_COLUMNS", "execute_run", "read_results", "sweep"]

#: The figures of each row, from the run's ``summary.json`` (and its time series).
FIGURES = (
    "peak_knee_angle_deg",
    "min_knee_angle_deg",
    "final_knee_angle_deg",
    "max_knee_speed_deg_s",
    "time_to_target_s",
    "peak_area_change",
    "muscle_volume_ratio_min",
    "muscle_volume_ratio_max",
    "min_fat_volume_ratio",
    "inverted_elements",
    "realtime_factor",
    "wall_time_s",
)

#: Columns that measure the machine (wall-clock), not the model: they differ run to run.
TIMING_COLUMNS = ("realtime_factor", "wall_time_s")

def _time_to_target(timeseries: Path, target_deg: float | None) -> float | None:
    """First time the knee reaches ``target_deg`` (from below when the knee starts below
    it, from above otherwise)."""
    if target_deg is None:
        return None
    times, angles = read_trajectory(timeseries)
    rising = target_deg >= angles[0]
    for t, angle in zip(times, angles):
        if (rising and angle >= target_deg) or (not rising and angle <= target_deg):
            return float(t)
    return None


def _failed(job: dict[str, Any], error: str) -> dict[str, Any]:
    """The row of a run that failed."""
    row: dict[str, Any] = {"run": job["id"], "index": job["index"], **job["params"]}
    row.update({k: None for k in FIGURES})
    row["error"] = error
    row["summary"] = None
    return row


def _figures(summary: dict[str, Any], time_to_target: float | None) -> dict[str, Any]:
    return {
        "peak_knee_angle_deg": summary["knee_angle_range_deg"][1],
        "min_knee_angle_deg": summary["knee_angle_range_deg"][0],
        "final_knee_angle_deg": summary["final_knee_angle_deg"],
        "max_knee_speed_deg_s": summary["max_knee_speed_deg_s"],
        "time_to_target_s": time_to_target,
        "peak_area_change": summary["max_abs_area_change"],
        "muscle_volume_ratio_min": summary["muscle_volume_ratio_range"][0],
        "muscle_volume_ratio_max": summary["muscle_volume_ratio_range"][1],
        "min_fat_volume_ratio": summary["min_fat_volume_ratio"],
        "inverted_elements": summary["inverted_elements"],
        "realtime_factor": summary["realtime_factor"],
        "wall_time_s": summary["wall_time_s"],
    }


def execute_run(job: dict[str, Any]) -> dict[str, Any]:
    """Runs one run (what each Ray task does) and returns its row, with ``summary``
    (``summary.json``'s content) beside it. A run that fails returns its error in the
    row. Frames are written straight into the run's folder when the sweep keeps them
    (on a cluster, that folder must be on storage every node sees); otherwise the run
    works in a temporary folder and returns what the driver writes."""
    keep = job["frames"]
    work = Path(job["run_dir"]) if keep else Path(tempfile.mkdtemp(prefix="myoslice-run-"))
    try:
        # One lattice per worker process for the sweep's model: the same bits, and most
        # of a short run's time saved.
        summary = run_scenario(job["scenario"], str(work), text=job["text"], reuse_model=True)
        ttt = _time_to_target(work / "timeseries.csv", job["target_knee_deg"])
        row: dict[str, Any] = {"run": job["id"], "index": job["index"], **job["params"]}
        row.update(_figures(summary, ttt))
        row["error"] = None
        row["summary"] = summary
        return row
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as e:  # a panic too: recorded in the table; the sweep goes on
        return _failed(job, f"{type(e).__name__}: {e}")
    finally:
        if not keep:
            shutil.rmtree(work, ignore_errors=True)


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, path)


class _Progress:
    """A one-line progress display with an ETA, on stderr."""

    def __init__(self, total: int, done: int, failed: int, show: bool) -> None:
        self.total, self.done, self.failed = total, done, failed
        self.start, self.first = time.monotonic(), done
        self.show = show
        self._draw()

    def tick(self, failed: bool) -> None:
        self.done += 1
        self.failed += failed
        self._draw()

    def _draw(self) -> None:
        if not self.show:
            return
        elapsed = time.monotonic() - self.start
        new = self.done - self.first
        left = self.total - self.done
        eta = f"{elapsed / new * left:.0f} s" if new else "?"
        width = 30
        filled = width * self.done // max(self.total, 1)
        sys.stderr.write(
            f"\r[{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} runs"
            f"  {self.failed} failed  {elapsed:.0f} s  eta {eta}   "
        )
        sys.stderr.flush()

    def close(self) -> None:
        if self.show:
            sys.stderr.write("\n")


def _open_folder(plan: SweepPlan, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    manifest = out / "sweep.json"
    doc = {
        "sweep_file": str(plan.path),
        "scenario": str(plan.scenario),
        "method": plan.method,
        "seed": plan.seed,
        "fingerprint": plan.fingerprint(),
        "runs": [{"run": r.id, "params": r.params} for r in plan.runs],
    }
    if manifest.exists():
        try:
            old = json.loads(manifest.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as e:
            raise InvalidInputError(f"{manifest}: unreadable ({e}); use another --out") from None
        if old.get("fingerprint") != doc["fingerprint"]:
            raise InvalidInputError(
                f"{out} holds another sweep's runs (its sweep.json differs from "
                f"{plan.path}'s plan): use another --out"
            )
    else:
        _write_atomic(manifest, json.dumps(doc, indent=1))


def _row(out: Path, run: Run) -> dict[str, Any]:
    """The row recorded for a run, or {} when there is none (or it cannot be read)."""
    try:
        row = json.loads((out / "runs" / run.id / "row.json").read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return {}
    return row if isinstance(row, dict) else {}


def _done(out: Path, run: Run, retry_failed: bool) -> bool:
    row = _row(out, run)
    return bool(row) and not (retry_failed and row.get("error") is not None)


def _record(out: Path, row: dict[str, Any]) -> None:
    folder = out / "runs" / row["run"]
    folder.mkdir(parents=True, exist_ok=True)
    summary = row.pop("summary", None)
    if summary is not None:
        _write_atomic(folder / "summary.json", json.dumps(summary, indent=1))
    _write_atomic(folder / "row.json", json.dumps(row))


def _jobs(plan: SweepPlan, out: Path, runs: Iterable[Run]) -> list[dict[str, Any]]:
    return [
        {
            "id": r.id,
            "index": r.index,
            "params": r.params,
            "scenario": str(plan.scenario),
            "text": plan.run_toml(r),
            "run_dir": str(out / "runs" / r.id),
            "frames": plan.frames,
            "target_knee_deg": plan.target_knee_deg,
        }
        for r in runs
    ]


def _serial(jobs: list[dict[str, Any]], done: Callable[[dict[str, Any]], None]) -> None:
    for job in jobs:
        done(execute_run(job))


def _on_ray(
    jobs: list[dict[str, Any]],
    done: Callable[[dict[str, Any]], None],
    address: str | None,
    workers: int | None,
) -> None:
    with ray_session(address, workers) as ray:
        # Retried when its worker or node dies; an error inside a run is in its row. One
        # thread per task also on a cluster this did not start.
        task = ray.remote(num_cpus=1, max_retries=5, runtime_env={"env_vars": RUN_ENV})(
            execute_run
        )
        pending = {task.remote(job): job for job in jobs}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            job = pending.pop(ready[0])
            try:
                row = ray.get(ready[0])
            except ray.exceptions.RayError as e:
                row = _failed(job, f"{type(e).__name__}: {e}")
            done(row)


def read_results(out: str | Path) -> Any:
    """The rows recorded in a sweep folder so far, as a ``pyarrow.Table`` sorted by run."""
    import pyarrow as pa  # type: ignore[import-untyped]

    rows = []
    for path in sorted(Path(out).glob("runs/*/row.json")):
        rows.append(json.loads(path.read_text(encoding="utf-8")))
    rows.sort(key=lambda r: r["index"])
    return pa.Table.from_pylist(rows)


def sweep(
    sweep_file: str | Path,
    out: str | Path,
    *,
    address: str | None = None,
    workers: int | None = None,
    serial: bool = False,
    retry_failed: bool = False,
    limit: int | None = None,
    progress: bool | None = None,
) -> Path:
    """Runs a sweep file's runs into the folder ``out`` and returns the Parquet table's
    path (``out/results.parquet``).

    ``address``: a Ray cluster to join (default: a local Ray in this process, with
    ``workers`` CPUs, default all). ``serial``: no Ray, one run after another in this
    process. Runs already recorded in ``out`` are skipped (``retry_failed`` runs the
    failed ones again); ``limit`` runs at most that many new runs and stops (the table
    then holds the runs done so far). ``progress`` shows a bar with an ETA on stderr
    (default: when stderr is a terminal).

    Raises :class:`~myoslice.errors.InvalidInputError` for a bad sweep file (a field the
    scenario does not have, a range with min > max, a value that is no number...) before
    any run starts.
    """
    import pyarrow.parquet as pq  # type: ignore[import-untyped]

    if workers is not None and workers < 1:
        raise InvalidInputError(f"workers = {workers}: expected at least 1")
    if limit is not None and limit < 0:
        raise InvalidInputError(f"limit = {limit}: expected 0 or more")
    plan = load_sweep(sweep_file)
    out = Path(out)
    _open_folder(plan, out)
    todo = [r for r in plan.runs if not _done(out, r, retry_failed)]
    todo_ids = {r.id for r in todo}
    skipped = [r for r in plan.runs if r.id not in todo_ids]
    failed = sum(_row(out, r).get("error") is not None for r in skipped)
    if limit is not None:
        todo = todo[:limit]
    show = sys.stderr.isatty() if progress is None else progress
    # The bar counts the runs recorded and those this call will run (limit included).
    bar = _Progress(len(skipped) + len(todo), len(skipped), failed, show)

    def done(row: dict[str, Any]) -> None:
        _record(out, row)
        bar.tick(row["error"] is not None)

    jobs = _jobs(plan, out, todo)
    if serial:
        _serial(jobs, done)
    elif jobs:
        _on_ray(jobs, done, address, workers)
    bar.close()
    table = read_results(out)
    target = out / "results.parquet"
    tmp = out / "results.parquet.tmp"
    pq.write_table(table, tmp)
    os.replace(tmp, target)
    return target
