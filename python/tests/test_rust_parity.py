"""The Python binding against the Rust command line: bit-for-bit the same numbers, and
no slower.

The reference is ``myoslice probe`` of ``<repo>/target/release/myoslice`` (build it with
``cargo build --release -p myoslice-cli``). A missing binary fails these tests, unless
``MYOSLICE_ALLOW_MISSING_CLI=1`` is set, which skips them. The speed comparison is
sensitive to other load on the machine; ``MYOSLICE_TIMING_RUNS`` (default 9) sets how many
interleaved runs it takes the best of.
"""

from __future__ import annotations

import json
import math
import os
import re
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from myoslice import Simulation, State

ROOT = Path(__file__).resolve().parents[2]
CLI = ROOT / "target" / "release" / "myoslice"
OVERHEAD_FILE = Path(__file__).resolve().parent / ".last_overhead.txt"

EXCITE = {"semimembranosus": 0.7, "vastus_lateralis": 0.2}
# Timings take the best of this many interleaved runs (more help on a busy machine).
RUNS = int(os.environ.get("MYOSLICE_TIMING_RUNS", "9"))


def cli() -> Path:
    if CLI.is_file() and os.access(CLI, os.X_OK):
        return CLI
    msg = (
        f"the Rust CLI {CLI} is missing: build it with `cargo build --release -p myoslice-cli` "
        "(or set MYOSLICE_ALLOW_MISSING_CLI=1 to skip the parity tests)"
    )
    if os.environ.get("MYOSLICE_ALLOW_MISSING_CLI") == "1":
        pytest.skip(msg)
    pytest.fail(msg)


def probe(steps: int, dt: float, excite: dict[str, float], tissue: bool = False) -> dict[str, Any]:
    """Runs ``myoslice probe`` and returns its JSON report."""
    args = [str(cli()), "probe", "--steps", str(steps), "--dt", repr(dt)]
    for name, value in excite.items():
        args += ["--excite", f"{name}={value!r}"]
    if tissue:
        args.append("--tissue")
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, check=False)
    if done.returncode != 0:
        pytest.fail(f"{' '.join(args)} failed ({done.returncode}):\n{done.stdout}\n{done.stderr}")
    try:
        report: dict[str, Any] = json.loads(done.stdout)
    except json.JSONDecodeError as e:
        pytest.fail(f"{' '.join(args)} printed no JSON ({e}):\n{done.stdout}\n{done.stderr}")
    return report


@pytest.fixture(scope="module")
def fresh_rigid() -> tuple[Simulation, State]:
    """A newly built rigid phantom (as the CLI builds it) and its initial checkpoint."""
    sim = Simulation.phantom(tissue=False)
    return sim, sim.state()


def python_run(sim: Simulation, steps: int, dt: float, excite: dict[str, float]) -> None:
    for name, value in excite.items():
        sim.set_excitation(name, value)
    sim.step(dt, n=steps)


@pytest.mark.parametrize(
    ("steps", "tissue"),
    [(300, False), (60, True)],
    ids=["rigid", "tissue"],
)
def test_bit_for_bit_parity(fresh_rigid: tuple[Simulation, State], steps: int, tissue: bool) -> None:
    dt = 0.001
    report = probe(steps, dt, EXCITE, tissue=tissue)
    if tissue:
        sim = Simulation.phantom(tissue=True)
    else:
        sim, initial = fresh_rigid
        sim.set_state(initial)
    python_run(sim, steps, dt, EXCITE)

    assert sim.time == report["time"]
    assert sim.knee_angle == report["knee_angle"], (sim.knee_angle, report["knee_angle"])
    assert sim.knee_velocity == report["knee_velocity"], (sim.knee_velocity, report["knee_velocity"])
    assert sim.forces.tolist() == report["forces"]
    if "activations" in report:
        assert sim.activations.tolist() == report["activations"]
    assert sim.knee_angle != 0.0  # the excitations did something


# The legacy-mangled symbol of the core's `Simulation::step`: its hash names the build of
# the core (it changes with the features its dependencies were built with).
STEP_SYMBOL = re.compile(rb"_ZN8myoslice10simulation8stepping[0-9A-Za-z_$.]*?4step17h([0-9a-f]{16})E")


def _core_build(path: Path) -> bytes:
    found: set[bytes] = {m.group(1) for m in STEP_SYMBOL.finditer(path.read_bytes())}
    assert len(found) == 1, f"{path}: expected one Simulation::step symbol, found {sorted(found)}"
    return found.pop()


def test_the_wheel_and_the_cli_link_one_build_of_the_core() -> None:
    # Two builds of the same core source ran the same steps 5-10 % apart; the timings
    # below compare like with like only if both link the same one (crates/workspace-hack).
    import myoslice._myoslice as ext

    assert ext.__file__ is not None
    wheel, reference = _core_build(Path(ext.__file__)), _core_build(cli())
    assert wheel == reference, (
        f"the wheel's core ({wheel.decode()}) is another build than the CLI's ({reference.decode()}): "
        "align the dependency features in crates/workspace-hack (cargo tree -e features)"
    )


def _best(times: list[float]) -> float:
    assert all(math.isfinite(t) and t >= 0.0 for t in times), times
    return min(times)


# One timing run of the binding, in a fresh interpreter as the CLI runs in a fresh process:
# inside the test process the heap left by earlier tests slowed the same Rust steps by up to
# 7 %, which is the process's history, not the binding's cost. Each timed call also reads the
# simulation's own step timers: the Rust side of the same call, in the same process.
PYTHON_RUN = """
import json, sys, time
from myoslice import Simulation
steps, dt, excite = int(sys.argv[1]), float(sys.argv[2]), json.loads(sys.argv[3])
sim = Simulation.phantom(tissue=False)
initial = sim.state()
def start():
    sim.set_state(initial)
    for name, value in excite.items():
        sim.set_excitation(name, value)
    sim.reset_timers()
out = {}
start()
t0 = time.perf_counter()
sim.step(dt, n=steps)
out["batched_s"] = time.perf_counter() - t0
out["batched_rust_s"] = sim.timers["wall_s"]
out["batched_calls"] = sim.timers["calls"]
start()
step = sim.step
t0 = time.perf_counter()
for _ in range(steps):
    step(dt)
out["looped_s"] = time.perf_counter() - t0
out["looped_rust_s"] = sim.timers["wall_s"]
out["knee_angle"] = sim.knee_angle
start()
t0 = time.perf_counter()
sim.step(dt * steps)
out["single_s"] = time.perf_counter() - t0
print(json.dumps(out))
"""


def python_timing(steps: int, dt: float, excite: dict[str, float], cwd: Path) -> dict[str, float]:
    """Times ``step(dt, n=steps)`` and a loop of ``steps`` single calls in a fresh interpreter."""
    args = [sys.executable, "-c", PYTHON_RUN, str(steps), repr(dt), json.dumps(excite)]
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, check=False, cwd=cwd)
    if done.returncode != 0:
        pytest.fail(f"the timing interpreter failed ({done.returncode}):\n{done.stdout}\n{done.stderr}")
    report: dict[str, float] = json.loads(done.stdout)
    return report


# Across two processes the very same Rust steps differ by more than the binding costs: best
# of 9 against best of 9, the Rust steps inside a Python process ran 2-8 % slower than in the
# CLI on this machine (heap and code layout, not the binding), single pairs up to 19 %, and
# once (2026-12-03) 15.4 % best against best, which failed the 1.15 bound this had then. So
# the 5 % bound is held where it measures the binding alone (the same process, the same
# machine code); the CLI bound only catches a wheel built wrong (a debug wheel is ten times
# slower).
BINDING_BOUND = 1.05
CLI_BOUND = 1.5
# A call from a Python loop may cost this much more than its Rust step (measured: under 1 us).
CALL_OVERHEAD_BOUND_US = 5.0


def test_throughput_and_call_overhead(tmp_path: Path) -> None:
    steps, dt = 1000, 0.001
    # Interleaved, so that both see the same load on the machine.
    runs: dict[str, list[float]] = {}
    for _ in range(RUNS):
        report = probe(steps, dt, EXCITE)
        runs.setdefault("cli", []).append(float(report["wall_s"]))
        timing = python_timing(steps, dt, EXCITE, tmp_path)
        # Same steps: the comparison would mean nothing if the two ran different motions.
        assert timing["knee_angle"] == report["knee_angle"]
        # One Rust `step` per step: the batched call loops in Rust, not in Python.
        assert timing["batched_calls"] == steps
        for key in ("batched_s", "batched_rust_s", "looped_s", "looped_rust_s", "single_s"):
            runs.setdefault(key, []).append(timing[key])
    best = {key: _best(times) for key, times in runs.items()}
    # The binding's own cost, run by run: the Python timer against the Rust one of the same call.
    binding = statistics.median(p / r for p, r in zip(runs["batched_s"], runs["batched_rust_s"]))
    call_us = statistics.median((p - r) / steps * 1e6 for p, r in zip(runs["looped_s"], runs["looped_rust_s"]))

    rows = [
        ("Rust CLI (probe wall_s)", best["cli"] * 1e3, "ms"),
        (f"Python sim.step({dt}, n={steps})", best["batched_s"] * 1e3, "ms"),
        ("  its Rust steps (sim.timers)", best["batched_rust_s"] * 1e3, "ms"),
        (f"Python loop of {steps} sim.step({dt})", best["looped_s"] * 1e3, "ms"),
        ("overhead per Python step() call", call_us, "us"),
        # One call for all the steps: one rollback copy instead of one per step.
        (f"Python sim.step({dt * steps:g}), one call", best["single_s"] * 1e3, "ms"),
    ]
    summary = f"{steps} steps of {dt * 1e3:g} ms, rigid phantom, best of {RUNS}:\n" + "".join(
        f"  {label:<38}{value:9.2f} {unit}\n" for label, value, unit in rows
    )
    summary += f"  binding over its own Rust steps: {100 * (binding - 1):+.2f} % (median run)\n"
    print(summary)
    OVERHEAD_FILE.write_text(summary)

    assert math.isfinite(call_us)
    assert binding <= BINDING_BOUND, f"the binding costs more than 5 % over its Rust steps:\n{summary}"
    assert call_us <= CALL_OVERHEAD_BOUND_US, f"a Python step() call costs too much:\n{summary}"
    assert best["batched_s"] <= best["cli"] * CLI_BOUND, f"Python is far slower than the CLI:\n{summary}"
