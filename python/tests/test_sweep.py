"""Parameter sweeps (``myoslice.sweep``): checked before any run, the same rows on a Ray
cluster as one after another, a lost node's runs retried, an interrupted sweep resumed
without a run done twice or missed, failures recorded while the others go on."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

import pytest

pytest.importorskip("ray", reason="sweeps on Ray need ray (see requirements-test.txt)")
pq = pytest.importorskip("pyarrow.parquet", reason="sweep tables need pyarrow")

import myoslice  # noqa: E402
from myoslice.errors import InvalidInputError  # noqa: E402
from myoslice.sweep import TIMING_COLUMNS, read_results, sweep  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "assets" / "scenarios"

# A short flexion with tissue (a few seconds per run on one thread), and one without.
FLEXION = """
[simulation]
duration_s = 0.2
[excitation]
hamstrings = [[0.0, 0.0], [0.1, 0.6]]
[output]
frames = 2
"""
QUICK = FLEXION + "[tissue]\nenabled = false\n"


def write_sweep(folder: Path, scenario: str, body: str) -> Path:
    (folder / "base.toml").write_text(scenario)
    path = folder / "sweep.toml"
    path.write_text('scenario = "base.toml"\n' + body)
    return path


SIXTEEN = """
method = "latin_hypercube"
runs = 16
seed = 11
target_knee_deg = 20.0
[parameters]
"body.mass_kg" = { min = 50.0, max = 90.0 }
"muscle.hamstrings.max_force_scale" = { min = 0.8, max = 1.3 }
"simulation.tendon" = ["rigid", "compliant"]
"""


def comparable(table: Any) -> list[dict[str, Any]]:
    """The rows without the wall-clock columns."""
    rows: list[dict[str, Any]] = table.to_pylist()
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in rows]


@pytest.fixture(scope="module")
def cluster() -> Iterator[Any]:
    """A Ray cluster on 127.0.0.1: a head and one more worker node, one CPU each."""
    from ray.cluster_utils import Cluster

    c = Cluster(
        initialize_head=True,
        head_node_args={"num_cpus": 1, "include_dashboard": False},
    )
    c.add_node(num_cpus=1)
    c.wait_for_nodes()
    try:
        yield c
    finally:
        c.shutdown()


RANDOM3 = 'method = "random"\nruns = 3\n[parameters]\n'
GRID = "[parameters]\n"


@pytest.mark.parametrize(
    ("body", "message"),
    [
        # Fields the scenario does not have.
        (RANDOM3 + '"body.mas_kg" = { min = 50.0, max = 90.0 }', "unknown field `mas_kg`"),
        (RANDOM3 + '"tisue.rate_hz" = { min = 10.0, max = 60.0 }', "unknown field `tisue`"),
        (RANDOM3 + '"excitation.hamstrings" = [1.0]', "simulation.excitation_scale"),
        # Ranges and values.
        (RANDOM3 + '"body.mass_kg" = { min = 90.0, max = 50.0 }', "min = 90.0 is greater than max = 50.0"),
        (RANDOM3 + '"body.mass_kg" = { min = "light", max = 90.0 }', "min = 'light': expected a finite number"),
        (RANDOM3 + '"simulation.tendon" = { min = 1, max = 2 }', "simulation.tendon"),
        (RANDOM3 + '"body.mass_kg" = []', "empty list"),
        (GRID + '"simulation.tendon" = ["rigid", 1]', "one kind"),
        (GRID + '"tissue.iterations" = { min = 2, max = 4, steps = 5 }', "repeat"),
        # Every run's settings, and the names (the first run's model is built).
        (GRID + '"simulation.initial_knee_deg" = [0.0, 400.0]', "initial_knee_deg = 400"),
        (GRID + '"muscle.hamstring.max_force_scale" = [1.0]', "hamstrings"),
        # The file's own keys and methods.
        ('method = "sobol"', "method = 'sobol'"),
        ('method = "random"', "runs = None"),
        ('runs = 3\n[parameters]\n"body.mass_kg" = [60.0]', "a grid runs every combination"),
        (GRID + '"body.mass_kg" = { min = 50.0, max = 90.0 }', "needs the range's steps"),
        ("repeat = 2", "unknown key(s) ['repeat']"),
    ],
)
def test_a_bad_sweep_file_is_refused_before_any_run(tmp_path: Path, body: str, message: str) -> None:
    path = write_sweep(tmp_path, QUICK, body + "\n")
    out = tmp_path / "out"
    with pytest.raises(InvalidInputError) as e:
        sweep(path, out, serial=True)
    assert message in str(e.value), str(e.value)
    assert not out.exists()


def test_a_sixteen_run_sweep_on_a_ray_cluster_gives_the_serial_rows_bit_for_bit(
    tmp_path: Path, cluster: Any
) -> None:
    path = write_sweep(tmp_path, FLEXION, SIXTEEN)
    on_ray = pq.read_table(sweep(path, tmp_path / "ray", address=cluster.address))
    serial = pq.read_table(sweep(path, tmp_path / "serial", serial=True))
    assert on_ray.num_rows == 16
    assert on_ray.column("error").null_count == 16
    assert comparable(on_ray) == comparable(serial)
    rows = on_ray.to_pylist()
    assert [r["run"] for r in rows] == [f"run-{i:04d}" for i in range(16)]
    # The parameters act: the strongest hamstrings flex further than the weakest.
    by_force = sorted(rows, key=lambda r: r["muscle.hamstrings.max_force_scale"])
    assert by_force[-1]["peak_knee_angle_deg"] > by_force[0]["peak_knee_angle_deg"]
    assert all(r["peak_area_change"] > 0.0 for r in rows)
    assert all(0.0 < r["time_to_target_s"] <= 0.2 for r in rows)
    summary = json.loads((tmp_path / "ray" / "runs" / "run-0003" / "summary.json").read_text())
    assert summary["knee_angle_range_deg"][1] == rows[3]["peak_knee_angle_deg"]


def test_a_worker_node_lost_mid_sweep_has_its_runs_retried_elsewhere(
    tmp_path: Path, cluster: Any
) -> None:
    path = write_sweep(tmp_path, FLEXION, SIXTEEN.replace("seed = 11", "seed = 12"))
    out = tmp_path / "ray"
    result: dict[str, Any] = {}

    def run() -> None:
        try:
            result["path"] = sweep(path, out, address=cluster.address)
        except BaseException as e:  # reported by the assertion below
            result["error"] = e

    worker = next(n for n in cluster.worker_nodes)
    t = threading.Thread(target=run)
    t.start()
    deadline = time.monotonic() + 300
    while len(list(out.glob("runs/*/row.json"))) < 3 and time.monotonic() < deadline:
        time.sleep(0.1)
    done_at_kill = len(list(out.glob("runs/*/row.json")))
    cluster.remove_node(worker, allow_graceful=False)
    t.join(timeout=600)
    assert done_at_kill < 16, "the sweep ended before the node was lost"
    assert not t.is_alive() and "error" not in result, result
    table = pq.read_table(result["path"])
    assert table.num_rows == 16
    assert table.column("error").null_count == 16, table.column("error").to_pylist()
    serial = pq.read_table(sweep(path, tmp_path / "serial", serial=True))
    assert comparable(table) == comparable(serial)


def test_an_interrupted_sweep_resumes_without_repeating_or_missing_a_run(tmp_path: Path) -> None:
    body = '[parameters]\n"body.mass_kg" = { min = 50.0, max = 80.0, steps = 6 }\n'
    path = write_sweep(tmp_path, QUICK, body)
    out = tmp_path / "out"
    sweep(path, out, serial=True, limit=2)
    first = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    assert sorted(first) == ["run-0000", "run-0001"]
    # A run cut off mid-way leaves a folder without its row: it is run again.
    (out / "runs" / "run-0002").mkdir()
    table = pq.read_table(sweep(path, out, serial=True))
    assert table.column("run").to_pylist() == [f"run-{i:04d}" for i in range(6)]
    again = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("runs/*/summary.json")}
    assert all(again[k] == v for k, v in first.items()), "a finished run was run again"
    # Started once more: nothing left to run, the same table.
    assert comparable(pq.read_table(sweep(path, out, serial=True))) == comparable(table)
    # Another sweep into the same folder is refused.
    other = write_sweep(tmp_path, QUICK, body.replace("80.0", "85.0"))
    with pytest.raises(InvalidInputError, match="another sweep"):
        sweep(other, out, serial=True)


def test_a_failed_run_is_recorded_and_the_others_go_on(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A run that fails once running (here the simulation refusing to go on, as when it
    # becomes non-finite): every input is valid, so it passes the checks.
    import myoslice.sweep as sweep_module

    real = sweep_module.run_scenario

    def failing(path: Any, out: Any, **kwargs: Any) -> Any:
        if tomllib.loads(kwargs["text"])["body"]["mass_kg"] == 70.0:
            raise myoslice.SimulationError("simulation became non-finite at t = 0.1 s")
        return real(path, out, **kwargs)

    monkeypatch.setattr(sweep_module, "run_scenario", failing)
    body = '[parameters]\n"body.mass_kg" = [60.0, 70.0, 80.0]\n'
    path = write_sweep(tmp_path, QUICK, body)
    table = pq.read_table(sweep(path, tmp_path / "out", serial=True))
    assert read_results(tmp_path / "out").num_rows == 3
    errors = table.column("error").to_pylist()
    assert errors[0] is None and errors[2] is None
    assert errors[1] == "SimulationError: simulation became non-finite at t = 0.1 s"
    assert table.column("peak_knee_angle_deg").to_pylist()[1] is None
    assert not (tmp_path / "out" / "runs" / "run-0001" / "summary.json").exists()
    # Started again: the failed run stays failed, unless asked to run again.
    monkeypatch.setattr(sweep_module, "run_scenario", real)
    again = pq.read_table(sweep(path, tmp_path / "out", serial=True))
    assert again.column("error").to_pylist()[1] is not None
    again = pq.read_table(sweep(path, tmp_path / "out", serial=True, retry_failed=True))
    assert again.column("error").null_count == 3


def test_the_command_line_runs_a_sweep_through_the_python_package(tmp_path: Path) -> None:
    cli = ROOT / "target" / "release" / "myoslice"
    if not cli.exists():
        if os.environ.get("MYOSLICE_ALLOW_MISSING_CLI") == "1":
            pytest.skip("myoslice CLI not built")
        pytest.fail(f"{cli} not found: build it with `cargo build --release -p myoslice-cli`")
    body = '[parameters]\n"muscle.semitendinosus.max_force_scale" = [0.9, 1.1]\n'
    path = write_sweep(tmp_path, QUICK, body)
    env = {**os.environ, "MYOSLICE_PYTHON": sys.executable}
    done = subprocess.run(
        [str(cli), "sweep", str(path), "--out", str(tmp_path / "out"), "--serial", "--quiet"],
        capture_output=True, text=True, env=env, timeout=600, check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "2 runs (0 failed)" in done.stdout
    assert pq.read_table(tmp_path / "out" / "results.parquet").num_rows == 2
    bad = write_sweep(tmp_path, QUICK, '[parameters]\n"body.mass_kg" = { min = 2.0, max = 1.0 }\n')
    done = subprocess.run(
        [str(cli), "sweep", str(bad), "--out", str(tmp_path / "bad"), "--serial"],
        capture_output=True, text=True, env=env, timeout=600, check=False,
    )
    assert done.returncode == 1 and "greater than max" in done.stderr, done.stderr


def test_run_scenario_writes_what_the_cli_writes(tmp_path: Path) -> None:
    scenario = tmp_path / "s.toml"
    scenario.write_text(QUICK)
    summary = myoslice.run_scenario(scenario, tmp_path / "run")
    on_disk = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary == on_disk
    assert summary["knee_angle_range_deg"][1] > 1.0
    # A kept lattice gives the same run, bit for bit (but for the wall-clock figures).
    first = myoslice.run_scenario(scenario, tmp_path / "a", reuse_model=True)
    reused = myoslice.run_scenario(scenario, tmp_path / "b", reuse_model=True)
    timing = {"wall_time_s", "realtime_factor", "muscles_wall_time_s", "tissue_wall_time_s"}
    strip = lambda d: {k: v for k, v in d.items() if k not in timing}  # noqa: E731
    assert strip(first) == strip(reused) == strip(summary)
    with pytest.raises(myoslice.MyoSliceError, match="duration_s"):
        myoslice.run_scenario(scenario, tmp_path / "bad", text="[simulation]\nduration_s = -1\n")
