"""How fast sweeps run: runs per minute serially and on a local Ray with one and two
workers, Ray's overhead per task, and how the time grows with the number of runs.

    python examples/sweep_bench.py [--runs 16] [--growth 16,64,256] [--json out.json]

The runs are 1-second knee flexions (``knee_flexion.toml`` cut to 1 s) with tissue, the
hamstrings' strength varied; the growth series uses the same flexion without tissue
(``hamstring_fit.toml``), so that 256 runs take minutes, not an hour. Prints a table;
``--json`` also writes the figures. The machine's load changes the figures: run it on
an idle machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from myoslice.sweep import sweep

SCENARIOS = Path(__file__).resolve().parents[2] / "assets" / "scenarios"


def sweep_file(folder: Path, scenario: Path, runs: int, duration: float | None) -> Path:
    path = folder / f"sweep-{scenario.stem}-{runs}.toml"
    extra = f'"simulation.duration_s" = [{duration!r}]\n' if duration else ""
    path.write_text(
        f'scenario = "{scenario}"\nmethod = "grid"\n[parameters]\n'
        f'"muscle.hamstrings.max_force_scale" = {{ min = 0.8, max = 1.2, steps = {runs} }}\n'
        + extra
    )
    return path


def timed(path: Path, out: Path, **kwargs: Any) -> float:
    t0 = time.perf_counter()
    sweep(path, out, progress=False, **kwargs)
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=16)
    ap.add_argument("--growth", default="16,64,256")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    os.environ.setdefault("RAYON_NUM_THREADS", "1")  # the serial runs use one thread too
    figures: dict[str, Any] = {"machine": f"{platform.node()} {os.cpu_count()} CPUs",
                               "date": time.strftime("%Y-%m-%d %H:%M")}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        flexion = sweep_file(folder, SCENARIOS / "knee_flexion.toml", args.runs, 1.0)
        walls = {
            "serial": timed(flexion, folder / "serial", serial=True),
            "ray, 1 worker": timed(flexion, folder / "ray1", workers=1),
            "ray, 2 workers": timed(flexion, folder / "ray2", workers=2),
        }
        per_minute = {k: 60.0 * args.runs / w for k, w in walls.items()}
        overhead = (walls["ray, 1 worker"] - walls["serial"]) / args.runs
        figures["flexion_runs"] = args.runs
        figures["runs_per_minute"] = per_minute
        figures["ray_overhead_per_task_s"] = overhead
        growth: dict[int, float] = {}
        for n in (int(x) for x in args.growth.split(",") if x):
            quick = sweep_file(folder, SCENARIOS / "hamstring_fit.toml", n, None)
            growth[n] = timed(quick, folder / f"growth{n}", workers=2)
        figures["growth_wall_s_2_workers"] = growth
    print(f"{figures['machine']}, {figures['date']}")
    print(f"{args.runs} knee flexions of 1 s with tissue:")
    for k, v in per_minute.items():
        print(f"  {k:15s} {v:6.1f} runs/min ({walls[k]:.1f} s)")
    print(f"  Ray overhead per task (1 worker against serial): {overhead:.2f} s")
    print("flexions without tissue, Ray with 2 workers:")
    for n, w in growth.items():
        print(f"  {n:4d} runs {w:7.1f} s  ({w / n:.2f} s per run)")
    if args.json:
        args.json.write_text(json.dumps(figures, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
