#!/usr/bin/env python3
"""MuJoCo peer of myoslice's `knee_hinge_16`: a one-hinge knee (Dempster shank, thigh fixed,
knee straight down under gravity) with the 16 muscles of assets/muscles.toml as MuJoCo muscle
actuators on fixed tendons (constant moment arms: flexors 3.5 cm, extensors 4.5 cm, others 1 cm).
Task: the 10 flexors excited at 0.6 for 1 s from full extension, 1 ms step. Prints the wall time
of one simulated second (best of 3) and the knee angle reached.

Mapping of the Hill parameters onto MuJoCo's muscle (see modeling.rst, "Muscles"):
- force = F_max cos(pennation) (MuJoCo has no pennation);
- L0 = optimal fibre length and the rigid tendon chosen so that the normalised fibre length is
  rest_fibre_length at full extension and changes by (moment arm x angle) / L0: the fixed tendon's
  length is coef * q (coef = -r for muscles that shorten with flexion, +r for extensors), so
  L_T = -rest_fibre_length * L0, lengthrange = L_T + range * L0 with range = (0.5, 1.5);
- vmax = max_contraction_velocity (optimal lengths per second, as MuJoCo's vmax in L0/s);
- lmin 0.33, lmax 1.72, fpmax 0.73, fvmax 1.8: least-squares fit of MuJoCo's piecewise-quadratic
  force-length and passive curves to De Groote et al. (2016) (the curves myoslice uses; active over
  L in [0.4, 1.8], passive over [1, 1.65]) and De Groote's force at maximal lengthening velocity;
- timeconst = (0.015, 0.060) s as De Groote 2016 (MuJoCo's activation scaling by 0.5 + 1.5 a is
  the same as theirs), tausmooth 0.2 for their tanh switch (b = 10).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

import knee_common as kc

try:
    import mujoco
    import numpy as np
except ImportError as e:  # pragma: no cover - setup problem
    sys.exit(f"mujoco_knee.py: {e}; run bench/peers/setup.sh and use bench/peers/.venv/bin/python")

RANGE = (0.5, 1.5)
LMIN, LMAX, FPMAX, FVMAX = 0.33, 1.72, 0.73, 1.8
TAUSMOOTH = 0.2


def model_xml(muscles: list[kc.Muscle], integrator: str) -> str:
    lo, hi = (math.radians(a) for a in kc.KNEE_RANGE_DEG)
    tendons, actuators = [], []
    for m in muscles:
        coef = -m.moment_arm if m.flexes else m.moment_arm
        tendons.append(f'    <fixed name="{m.name}"><joint joint="knee" coef="{coef:.6g}"/></fixed>')
        lt = -m.rest_norm * m.lopt
        lr = (lt + RANGE[0] * m.lopt, lt + RANGE[1] * m.lopt)
        actuators.append(
            f'    <muscle name="{m.name}" tendon="{m.name}" force="{m.fmax * math.cos(m.pennation):.6g}" '
            f'range="{RANGE[0]} {RANGE[1]}" lengthrange="{lr[0]:.6g} {lr[1]:.6g}" '
            f'lmin="{LMIN}" lmax="{LMAX}" vmax="{m.vmax:.6g}" fpmax="{FPMAX}" fvmax="{FVMAX}" '
            f'timeconst="{kc.TAU_ACTIVATION} {kc.TAU_DEACTIVATION}" tausmooth="{TAUSMOOTH}"/>'
        )
    it, il = kc.SHANK_I_TRANSVERSE, kc.SHANK_I_LONG
    nl = "\n"
    # z up; the shank hangs along -z; +y is the hinge axis, so positive q swings the ankle to -x
    # (posterior): flexion.
    return f"""
<mujoco model="knee_hinge_16">
  <compiler angle="radian"/>
  <option timestep="{kc.DT}" integrator="{integrator}" gravity="0 0 {-kc.GRAVITY}"/>
  <worldbody>
    <body name="shank">
      <joint name="knee" type="hinge" axis="0 1 0" range="{lo} {hi}" damping="{kc.KNEE_DAMPING}"/>
      <inertial pos="0 0 {-kc.SHANK_COM:.6g}" mass="{kc.SHANK_MASS:.6g}" diaginertia="{it:.6g} {it:.6g} {il:.6g}"/>
    </body>
  </worldbody>
  <tendon>
{nl.join(tendons)}
  </tendon>
  <actuator>
{nl.join(actuators)}
  </actuator>
</mujoco>
"""


def run(repeats: int, integrator: str) -> dict:
    muscles = kc.load_muscles()
    model = mujoco.MjModel.from_xml_string(model_xml(muscles, integrator))
    data = mujoco.MjData(model)
    ctrl = np.array([kc.EXCITATION if m.excited else 0.0 for m in muscles])
    nstep = round(kc.DURATION / kc.DT)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_resetData(model, data)
    mujoco.mj_getState(model, data, state0, spec)

    # 1) Python loop around mj_step (what a user script does).
    best_py, angle_py = float("inf"), float("nan")
    for _ in range(repeats):
        mujoco.mj_resetData(model, data)
        data.ctrl[:] = ctrl
        t0 = time.perf_counter()
        for _ in range(nstep):
            mujoco.mj_step(model, data)
        best_py = min(best_py, time.perf_counter() - t0)
        angle_py = math.degrees(data.qpos[0])

    # 2) The same steps in C through mujoco.rollout (no Python per step): the engine's own cost.
    best_c, angle_c, peak = float("inf"), float("nan"), float("nan")
    try:
        from mujoco import rollout

        controls = np.tile(ctrl, (1, nstep, 1))
        with rollout.Rollout(nthread=0) as r:
            for _ in range(repeats):
                t0 = time.perf_counter()
                states, _ = r.rollout(model, data, state0[None, :], controls, nstep=nstep)
                best_c = min(best_c, time.perf_counter() - t0)
        qadr = 1  # FULLPHYSICS state = [time, qpos, qvel, act, ...]
        angle_c = math.degrees(states[0, -1, qadr])
        peak = math.degrees(states[0, :, qadr].max())
    except Exception as e:  # pragma: no cover - older bindings
        print(f"mujoco_knee.py: rollout unavailable ({e}); reporting the Python loop only", file=sys.stderr)
    if not math.isfinite(angle_py):
        raise RuntimeError("simulation diverged")
    seconds = best_c if math.isfinite(best_c) else best_py
    return {
        "name": "knee_hinge_16",
        "engine": f"MuJoCo {mujoco.__version__}",
        "integrator": integrator,
        "timestep": kc.DT,
        "steps": nstep,
        "seconds": seconds,
        "per_unit_ns": seconds * 1e9 / nstep,
        "unit": "ns per 1 ms step",
        "realtime_factor": kc.DURATION / seconds,
        "timing": "mujoco.rollout (C loop)" if math.isfinite(best_c) else "Python loop",
        "seconds_python_loop": best_py,
        "realtime_factor_python_loop": kc.DURATION / best_py,
        "knee_angle_deg": angle_py,
        "knee_angle_rollout_deg": angle_c,
        "knee_peak_deg": peak,
        **kc.summary(muscles),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=kc.REPEATS)
    ap.add_argument("--integrator", default="implicitfast",
                    help="MuJoCo integrator (default implicitfast; Euler, RK4, implicit, discrete also work)")
    ap.add_argument("--print-xml", action="store_true", help="print the generated MJCF and exit")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args()
    if a.print_xml:
        print(model_xml(kc.load_muscles(), a.integrator))
        return
    r = run(a.repeats, a.integrator)
    if a.json:
        print(json.dumps(r))
        return
    print(f"{r['engine']}: one-hinge knee, {r['muscles']} muscles (fixed tendons), integrator {r['integrator']}, "
          f"dt {kc.DT * 1e3:g} ms; defaulted: {', '.join(r['defaulted']) or 'none'}")
    print(f"  1 s simulated, best of {a.repeats}: {r['seconds'] * 1e3:.2f} ms with {r['timing']} "
          f"({r['realtime_factor']:.0f} x realtime, {r['per_unit_ns']:.0f} ns/step); "
          f"Python loop {r['seconds_python_loop'] * 1e3:.2f} ms ({r['realtime_factor_python_loop']:.0f} x realtime)")
    print(f"  knee at 1 s: {r['knee_angle_deg']:.1f} deg (peak {r['knee_peak_deg']:.1f} deg)")


if __name__ == "__main__":
    main()
