#!/usr/bin/env python3
"""Side-by-side benchmark: myoslice against MuJoCo 4 and OpenSim 4.6, measured in the same run.

    bench/peers/setup.sh && bench/peers/.venv/bin/python bench/peers/compare.py

Runs `target/release/myoslice bench --json` (if built), then mujoco_fat.py, mujoco_knee.py and
opensim_knee.py one after another (never in parallel), and prints a markdown table with the date,
the machine and notes on what is not like for like. Ratios are "peer time / myoslice time": above 1
means myoslice is faster.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
DEFAULT_BIN = REPO / "target" / "release" / "myoslice"
TIMEOUT = 900  # s per program

# myoslice's tissue defaults (crates/myoslice/src/tissue/mod.rs, TissueConfig::default).
TISSUE_RATE_HZ = 30
TISSUE_ITERATIONS = 6
MUJOCO_FAT_DT = 0.002


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def machine() -> dict:
    u = platform.uname()
    load = ""
    try:
        load = Path("/proc/loadavg").read_text().split()[:3]
        load = " ".join(load)
    except OSError:
        pass
    return {
        "uname": f"{u.system} {u.release} {u.machine}",
        "cpu": cpu_model(),
        "logical_cores": os.cpu_count(),
        "python": platform.python_version(),
        "loadavg_at_start": load,
    }


def run_json(cmd: list[str], what: str) -> dict | None:
    print(f"[compare] running {what} ...", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, cwd=HERE)
    except subprocess.TimeoutExpired:
        print(f"[compare] {what}: timed out after {TIMEOUT} s", file=sys.stderr)
        return None
    except OSError as e:
        print(f"[compare] {what}: cannot run ({e})", file=sys.stderr)
        return None
    if p.returncode != 0:
        print(f"[compare] {what} failed (exit {p.returncode}):\n{p.stderr.strip()}", file=sys.stderr)
        return None
    try:
        # The JSON is the last thing printed; tolerate log lines before it.
        text = p.stdout.strip()
        start = text.find("{")
        out = json.loads(text[start:])
    except (ValueError, json.JSONDecodeError) as e:
        print(f"[compare] {what}: could not parse JSON ({e}); output was:\n{p.stdout[:2000]}", file=sys.stderr)
        return None
    print(f"[compare] {what} done in {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    return out


def case(bench: dict | None, name: str) -> dict | None:
    if not bench:
        return None
    for c in bench.get("cases", []):
        if c.get("name") == name:
            return c
    return None


def knee_angle_from_note(c: dict | None) -> float | None:
    if not c:
        return None
    for key in ("knee_angle_deg", "knee_deg"):
        if isinstance(c.get(key), (int, float)):
            return float(c[key])
    m = re.search(r"knee reached\s+(-?[0-9.]+)", str(c.get("note", "")))
    return float(m.group(1)) if m else None


def fmt(v: float | None, unit: str = "", digits: int = 1) -> str:
    if v is None:
        return "—"
    if abs(v) >= 1e4:
        s = f"{v:,.0f}"
    else:
        s = f"{v:.{digits}f}"
    return f"{s} {unit}".strip()


def ratio(peer: float | None, ours: float | None) -> str:
    if peer is None or ours is None or ours <= 0:
        return "—"
    return f"{peer / ours:.2f}×"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--myoslice", type=Path, default=DEFAULT_BIN, help=f"the CLI binary (default {DEFAULT_BIN})")
    ap.add_argument("--skip-myoslice", action="store_true", help="peers only")
    ap.add_argument("--out", type=Path, help="also write every raw result to this JSON file")
    a = ap.parse_args()

    py = sys.executable
    mach = machine()
    date = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")

    ours = None
    ours_msg = ""
    if a.skip_myoslice:
        ours_msg = "myoslice skipped (--skip-myoslice)."
    elif a.myoslice.is_file() and os.access(a.myoslice, os.X_OK):
        ours = run_json([str(a.myoslice), "bench", "--json"], "myoslice bench --json")
        if ours is None:
            ours_msg = f"`{a.myoslice} bench --json` failed; see the messages above."
    else:
        ours_msg = (f"myoslice binary not found at {a.myoslice}: build it first with "
                    "`cargo build --release -p myoslice-cli` (peer numbers are printed anyway).")
        print(f"[compare] {ours_msg}", file=sys.stderr)

    fat = run_json([py, str(HERE / "mujoco_fat.py"), "--json"], "MuJoCo flexcomp grid")
    mjk = run_json([py, str(HERE / "mujoco_knee.py"), "--json"], "MuJoCo knee")
    osk = run_json([py, str(HERE / "opensim_knee.py"), "--json"], "OpenSim knee")

    fk = case(ours, "fat_kernel_840")
    kk = case(ours, "knee_hinge_16")

    rows: list[tuple[str, str, str, str, str, str]] = []
    # --- the fat grid -------------------------------------------------------------------------
    our_ns = fk.get("per_unit_ns") if fk else None
    mj_ns = fat.get("per_unit_ns") if fat else None
    rows.append(("840-hex grid: ns per element per solver update (1 shape-matching iteration vs 1 MuJoCo step)",
                 fmt(our_ns, "ns"), fmt(mj_ns, "ns"), "—", ratio(mj_ns, our_ns), "—"))
    our_upd = our_ns * 840 * TISSUE_ITERATIONS / 1e3 if our_ns else None
    mj_step = fat.get("per_step_us") if fat else None
    rows.append((f"840-hex grid: µs per tissue update ({TISSUE_ITERATIONS} iterations vs 1 step of 2 ms)",
                 fmt(our_upd, "µs"), fmt(mj_step, "µs"), "—", ratio(mj_step, our_upd), "—"))
    our_sec = our_upd * TISSUE_RATE_HZ / 1e3 if our_upd else None
    mj_sec = mj_step * (1 / MUJOCO_FAT_DT) / 1e3 if mj_step else None
    rows.append((f"840-hex grid: ms wall per simulated s ({TISSUE_RATE_HZ} Hz × {TISSUE_ITERATIONS} vs 500 Hz)",
                 fmt(our_sec, "ms"), fmt(mj_sec, "ms"), "—", ratio(mj_sec, our_sec), "—"))
    # --- the knee -----------------------------------------------------------------------------
    our_s = kk.get("seconds") if kk else None
    mj_s = mjk.get("seconds") if mjk else None
    os_s = osk.get("seconds") if osk else None
    rows.append(("16-muscle knee: ms wall per simulated s (1 ms steps, best of 3)",
                 fmt(our_s * 1e3 if our_s else None, "ms", 2), fmt(mj_s * 1e3 if mj_s else None, "ms", 2),
                 fmt(os_s * 1e3 if os_s else None, "ms", 1), ratio(mj_s, our_s), ratio(os_s, our_s)))
    rf = lambda d: d.get("realtime_factor") if d else None  # noqa: E731
    rows.append(("16-muscle knee: × realtime", fmt(rf(kk), "", 0), fmt(rf(mjk), "", 0), fmt(rf(osk), "", 1),
                 "", ""))
    rows.append(("16-muscle knee: knee angle at 1 s (deg)", fmt(knee_angle_from_note(kk)),
                 fmt(mjk.get("knee_angle_deg") if mjk else None), fmt(osk.get("knee_angle_deg") if osk else None),
                 "", ""))
    mj_py = mjk.get("seconds_python_loop") if mjk else None
    os_rk = osk.get("seconds_rkmerson") if osk else None
    rows.append(("16-muscle knee, variants: MuJoCo Python mj_step loop; OpenSim RK-Merson (ms per simulated s)",
                 "—", fmt(mj_py * 1e3 if mj_py else None, "ms", 2), fmt(os_rk * 1e3 if os_rk else None, "ms", 1),
                 ratio(mj_py, our_s), ratio(os_rk, our_s)))

    engines = {
        "myoslice": (f"{ours.get('threads', '?')} threads" if ours else "not run"),
        "MuJoCo": (fat or mjk or {}).get("engine", "not run"),
        "OpenSim": (osk or {}).get("engine", "not run"),
    }
    print(f"## myoslice vs MuJoCo vs OpenSim — {date}")
    print()
    print(f"- Machine: {mach['cpu']}, {mach['logical_cores']} logical cores, {mach['uname']}, "
          f"Python {mach['python']}; load average at start {mach['loadavg_at_start']}")
    if ours:
        print(f"- myoslice: `{a.myoslice.name} bench --json` ({ours.get('machine', '')}, {ours.get('date', '')}, "
              f"{engines['myoslice']})")
    else:
        print(f"- myoslice: {ours_msg}")
    print(f"- Peers: {engines['MuJoCo']} (single thread), {engines['OpenSim']} (single thread)")
    if fat:
        print(f"- MuJoCo grid: flexcomp grid dim 3, {fat['vertices']} vertices, {fat['tetrahedra']} tetrahedra "
              f"({fat['hexahedra']} cube cells), {fat['dofs']} dofs, integrator {fat['integrator']}, "
              f"solver {fat['solver']}, dt {fat['timestep'] * 1e3:g} ms, E {fat['young_pa']:g} Pa, "
              f"ν {fat['poisson']:g}, Rayleigh damping {fat['damping_s']:g} s, no contacts, one end face pinned, "
              f"under gravity (sank {fat['tip_drop_m'] * 100:.0f} cm); "
              f"{fat['per_tet_ns']:.0f} ns per tetrahedron-step")
    if mjk:
        print(f"- MuJoCo knee: integrator {mjk['integrator']}, timed with {mjk['timing']}")
    if osk:
        print(f"- OpenSim knee: {osk['integrator']}; defaulted muscles: {', '.join(osk['defaulted']) or 'none'}")
    print()
    print("| case | myoslice | MuJoCo | OpenSim | MuJoCo / myoslice | OpenSim / myoslice |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for r in rows:
        print("| " + " | ".join(c.replace("|", "/") for c in r) + " |")
    print()
    print("Ratios are peer time / myoslice time (above 1: myoslice faster). Not like for like:")
    print("- The grid: myoslice's fat is shape matching (per hexahedron a warm-started rotation of the polar "
          "decomposition, vertices pulled toward the rotated rest shapes; single precision, no mass matrix, no "
          "stress), not FEM. MuJoCo splits each cube into tetrahedra and integrates Saint Venant-Kirchhoff "
          "elasticity implicitly (discrete integrator: a Newton solve over 3 dofs per vertex each step, double "
          "precision, with gravity and the pins). One MuJoCo step does far more physics than one shape-matching "
          "iteration, and converges where shape matching needs several iterations. Both effectively run on one "
          "thread here (840 hexahedra fit in one of myoslice's 2,048-element parallel blocks).")
    print("- The knee: MuJoCo tendons are rigid and its muscle is its own piecewise-quadratic FLV curve "
          "(fitted to De Groote 2016), with no pennation (force scaled by cos of the pennation angle) and "
          "exactly constant moment arms. OpenSim uses DeGrooteFregly2016Muscle with a rigid tendon and "
          "point-to-point paths (flexor moment arms vary with angle; extensors wrap a 4.5 cm cylinder). "
          "myoslice's knee_hinge_16 uses its own muscle paths on the phantom (wrapping, chains of mass "
          "points), not fixed moment arms, so the knee angles need not agree; they are printed to show the three do "
          "comparable work. popliteus and plantaris have no catalogue numbers: the peers give them 100 N, "
          "5 cm, 5 cm, 0°.")
    if a.out:
        a.out.write_text(json.dumps({"date": date, "machine": mach, "myoslice": ours, "mujoco_fat": fat,
                                     "mujoco_knee": mjk, "opensim_knee": osk}, indent=2))
        print(f"\n(raw results written to {a.out})")
    sys.stdout.flush()
    return 0 if (fat and mjk and osk) else 1


if __name__ == "__main__":
    sys.exit(main())
