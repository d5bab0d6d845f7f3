#!/usr/bin/env python3
"""MuJoCo peer of myoslice's `fat_kernel_840`: the same 20 x 7 x 6 cell grid (21 x 8 x 7 vertices,
1 cm spacing) as a 3-D `flexcomp type="grid"`, pinned at one end and hanging under gravity,
integrator "discrete", 2 ms step. Prints wall time per simulated step and per element-step.

Not like for like: MuJoCo splits each cube cell into tetrahedra and runs a Saint Venant-Kirchhoff
FEM with an implicit (discrete) integrator and a Newton solve per step; myoslice runs one
shape-matching iteration (a polar decomposition per hexahedron), no FEM, no mass matrix.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

try:
    import mujoco
    import numpy as np
except ImportError as e:  # pragma: no cover - setup problem
    sys.exit(f"mujoco_fat.py: {e}; run bench/peers/setup.sh and use bench/peers/.venv/bin/python")

CELLS = (20, 7, 6)  # hexahedra per axis, as FatSolver::grid(20, 7, 6, 0.01)
SPACING = 0.01  # m
N_HEX = CELLS[0] * CELLS[1] * CELLS[2]  # 840
DENSITY = 900.0  # kg/m^3, fat
YOUNG = 1.0e4  # Pa, soft fat-like
POISSON = 0.3
DAMPING = 2.0e-3  # Rayleigh stiffness-proportional damping, s
DT = 0.002


def model_xml(integrator: str, solver: str) -> str:
    count = f"{CELLS[0] + 1} {CELLS[1] + 1} {CELLS[2] + 1}"
    mass = DENSITY * N_HEX * SPACING**3
    # Pin the whole x = 0 face (grid coordinates 0 0 0 .. 0 7 6): a block hanging off a wall.
    pin = f"0 0 0 0 {CELLS[1]} {CELLS[2]}"
    return f"""
<mujoco model="fat_grid_840">
  <option timestep="{DT}" integrator="{integrator}" solver="{solver}" gravity="0 0 -9.81"/>
  <worldbody>
    <flexcomp name="fat" type="grid" dim="3" count="{count}" spacing="{SPACING} {SPACING} {SPACING}"
              mass="{mass:.6f}" radius="0.001" dof="full">
      <contact contype="0" conaffinity="0" selfcollide="none"/>
      <elasticity young="{YOUNG}" poisson="{POISSON}" damping="{DAMPING}"/>
      <pin gridrange="{pin}"/>
    </flexcomp>
  </worldbody>
</mujoco>
"""


def build(integrator: str, solver: str) -> tuple["mujoco.MjModel", str]:
    """Compiles the model; falls back to implicit if this MuJoCo lacks 'discrete' (it should not)."""
    try:
        return mujoco.MjModel.from_xml_string(model_xml(integrator, solver)), integrator
    except ValueError as e:
        if integrator == "discrete" and "integrator" in str(e).lower():
            print(f"mujoco_fat.py: integrator 'discrete' rejected ({e}); using 'implicit'", file=sys.stderr)
            return mujoco.MjModel.from_xml_string(model_xml("implicit", solver)), "implicit"
        raise


def run(steps: int, repeats: int, integrator: str, solver: str) -> dict:
    model, _ = build(integrator, solver)
    used = mujoco.mjtIntegrator(model.opt.integrator).name.removeprefix("mjINT_").lower()
    assert model.nflex == 1, "expected one flex"
    n_vert = int(model.flex_vertnum[0])
    n_elem = int(model.flex_elemnum[0])
    data = mujoco.MjData(model)
    best = float("inf")
    sag = float("nan")
    for _ in range(repeats):
        mujoco.mj_resetData(model, data)
        t0 = time.perf_counter()
        for _ in range(steps):
            mujoco.mj_step(model, data)
        best = min(best, time.perf_counter() - t0)
        # How far the lowest vertex dropped below the grid's bottom face (shows it is simulated).
        sag = float(-CELLS[2] * SPACING / 2 - data.flexvert_xpos[:, 2].min())
    if not np.all(np.isfinite(data.qpos)):
        raise RuntimeError("simulation diverged (non-finite qpos)")
    per_step = best / steps
    return {
        "name": "fat_grid_840",
        "engine": f"MuJoCo {mujoco.__version__}",
        "integrator": used,
        "solver": solver,
        "timestep": DT,
        "steps": steps,
        "seconds": best,
        "per_step_us": per_step * 1e6,
        "per_unit_ns": per_step * 1e9 / N_HEX,
        "unit": "ns per hexahedron-step",
        "per_tet_ns": per_step * 1e9 / n_elem,
        "hexahedra": N_HEX,
        "vertices": n_vert,
        "tetrahedra": n_elem,
        "dofs": int(model.nv),
        "realtime_factor": steps * DT / best,
        "tip_drop_m": sag,
        "young_pa": YOUNG,
        "poisson": POISSON,
        "damping_s": DAMPING,
        "density": DENSITY,
    }


def main() -> None:
    global YOUNG, POISSON
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=500, help="steps per timed run (default 500 = 1 s simulated)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs; the minimum is kept")
    ap.add_argument("--integrator", default="discrete")
    ap.add_argument("--solver", default="Newton")
    ap.add_argument("--young", type=float, default=YOUNG, help=f"Young's modulus, Pa (default {YOUNG:g})")
    ap.add_argument("--poisson", type=float, default=POISSON, help=f"Poisson's ratio (default {POISSON:g})")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args()
    YOUNG, POISSON = a.young, a.poisson
    r = run(a.steps, a.repeats, a.integrator, a.solver)
    if a.json:
        print(json.dumps(r))
        return
    print(f"{r['engine']}: 3-D flexcomp grid {r['vertices']} vertices, {r['tetrahedra']} tetrahedra "
          f"({r['hexahedra']} cube cells), {r['dofs']} dofs, integrator {r['integrator']}, solver {r['solver']}, "
          f"dt {DT * 1e3:g} ms")
    print(f"  best of {a.repeats} x {a.steps} steps: {r['seconds']:.3f} s = {r['per_step_us']:.1f} us/step, "
          f"{r['per_unit_ns']:.1f} ns per hexahedron-step ({r['per_tet_ns']:.1f} ns per tetrahedron-step), "
          f"{r['realtime_factor']:.2f} x realtime; E {YOUNG:g} Pa, nu {POISSON:g}: the lowest vertex sank "
          f"{r['tip_drop_m'] * 100:.1f} cm under gravity")


if __name__ == "__main__":
    main()
