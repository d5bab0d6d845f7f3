#!/usr/bin/env python3
"""OpenSim peer of myoslice's `knee_hinge_16`: a one-DOF pin-joint knee (Dempster shank, ground as
the thigh, knee straight down under gravity) built with the Python API, with the 16 muscles of
assets/muscles.toml as DeGrooteFregly2016Muscle (the curves myoslice's Hill model uses) with a rigid
tendon. Task: the 10 flexors excited at 0.6 for 1 s from full extension; fixed 1 ms explicit-Euler
steps (plus OpenSim's default error-controlled Runge-Kutta-Merson for reference). Prints the wall
time of one simulated second (best of 3) and the knee angle reached.

Geometry (the frame's +X is the side the ankle swings to in flexion, i.e. posterior here; +Y up,
the pin's Z the medio-lateral hinge axis):
- flexors and the two 'other' muscles: a straight path from the thigh (ground) at (r, h) to the
  shank at (r, -b), b = the catalogue's insertion_below_knee_m or 3 cm for flexors, 1 cm for the
  others: moment arm r at full extension (3.5 cm flexors, 1 cm others), then about
  r cos(q) + b sin(q), so it rises and falls as the knee flexes (printed at 0/45/90 degrees);
- extensors: (-r, h) to (-r, -3 cm) over a cylinder of radius r = 4.5 cm about the hinge axis
  (the patellar mechanism), so the moment arm stays 4.5 cm once the path wraps;
- h is chosen so the path at full extension is tendon slack length + fibre at rest_fibre_length
  optimal lengths (pennated), as in myoslice's rest-pose scaling.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

import knee_common as kc

try:
    import opensim as osim
except ImportError as e:  # pragma: no cover - setup problem
    sys.exit(f"opensim_knee.py: {e}; run bench/peers/setup.sh and use bench/peers/.venv/bin/python")

EXTENSOR_INSERTION = 0.03  # m below the knee axis (tibial tuberosity side)
OTHER_INSERTION = 0.01  # m below the knee axis for the two 'other' muscles
LIMIT_STIFFNESS = 50.0  # N m / degree beyond 0 and 140 degrees
LIMIT_DAMPING = 0.5  # N m s / degree
LIMIT_TRANSITION = 1.0  # degrees
DEFAULT_ACTIVATION = 1e-3  # DeGrooteFregly2016Muscle requires > 0 (MuJoCo and myoslice start at 0)


def build(muscles: list[kc.Muscle]) -> "osim.Model":
    model = osim.Model()
    model.setName("knee_hinge_16")
    model.setGravity(osim.Vec3(0, -kc.GRAVITY, 0))
    ground = model.getGround()
    it, il = kc.SHANK_I_TRANSVERSE, kc.SHANK_I_LONG
    shank = osim.Body("shank", kc.SHANK_MASS, osim.Vec3(0, -kc.SHANK_COM, 0), osim.Inertia(it, il, it))
    model.addBody(shank)
    knee = osim.PinJoint("knee", ground, osim.Vec3(0), osim.Vec3(0), shank, osim.Vec3(0), osim.Vec3(0))
    coord = knee.updCoordinate()
    coord.setName("knee_flexion")
    lo, hi = (math.radians(a) for a in kc.KNEE_RANGE_DEG)
    coord.setRangeMin(lo)
    coord.setRangeMax(hi)
    coord.setDefaultValue(0.0)
    model.addJoint(knee)

    limit = osim.CoordinateLimitForce("knee_flexion", kc.KNEE_RANGE_DEG[1], LIMIT_STIFFNESS,
                                      kc.KNEE_RANGE_DEG[0], LIMIT_STIFFNESS, LIMIT_DAMPING, LIMIT_TRANSITION)
    limit.setName("knee_limit")
    model.addForce(limit)
    damping = osim.SpringGeneralizedForce("knee_flexion")
    damping.setName("knee_damping")
    damping.setStiffness(0.0)
    damping.setViscosity(kc.KNEE_DAMPING)
    model.addForce(damping)

    patella = osim.WrapCylinder()
    patella.setName("patella")
    patella.set_radius(kc.MOMENT_ARM["extensor"])
    patella.set_length(0.2)
    patella.set_quadrant("-x")
    ground.addWrapObject(patella)

    controller = osim.PrescribedController()
    controller.setName("excitation")
    for m in muscles:
        mus = osim.DeGrooteFregly2016Muscle()
        mus.setName(m.name)
        mus.set_max_isometric_force(m.fmax)
        mus.set_optimal_fiber_length(m.lopt)
        mus.set_tendon_slack_length(m.lts)
        mus.set_pennation_angle_at_optimal(m.pennation)
        mus.set_max_contraction_velocity(m.vmax)
        mus.set_ignore_tendon_compliance(True)
        mus.set_activation_time_constant(kc.TAU_ACTIVATION)
        mus.set_deactivation_time_constant(kc.TAU_DEACTIVATION)
        mus.set_fiber_damping(kc.FIBRE_DAMPING)
        mus.set_default_activation(DEFAULT_ACTIVATION)
        lmt = m.mtu_length_at_rest()
        r = m.moment_arm
        if m.group == "flexor":
            b = m.insertion_below_knee
            x = r
        elif m.flexes:  # 'other': keep the moment arm near 1 cm
            b = OTHER_INSERTION
            x = r
        else:
            b = EXTENSOR_INSERTION
            x = -r
        h = lmt - b
        if h <= 0:
            raise RuntimeError(f"{m.name}: path at rest ({lmt:.3f} m) shorter than the insertion depth")
        mus.addNewPathPoint(f"{m.name}_origin", ground, osim.Vec3(x, h, 0))
        mus.addNewPathPoint(f"{m.name}_insertion", shank, osim.Vec3(x, -b, 0))
        if not m.flexes:
            mus.updGeometryPath().addPathWrap(patella)
        model.addForce(mus)
        if m.excited:
            controller.addActuator(mus)
            controller.prescribeControlForActuator(m.name, osim.Constant(kc.EXCITATION))
    model.addController(controller)
    model.finalizeConnections()
    return model


def simulate(model: "osim.Model", method: str) -> tuple[float, float]:
    """One simulated second from full extension; returns (wall seconds, knee angle deg)."""
    state = model.initSystem()
    model.getCoordinateSet().get("knee_flexion").setValue(state, 0.0)
    model.realizeVelocity(state)
    manager = osim.Manager(model)
    manager.setRecordStatesTrajectory(False)
    manager.setWriteToStorage(False)
    if method == "euler":
        manager.setIntegratorMethod(osim.Manager.IntegratorMethod_ExplicitEuler)
        manager.setIntegratorFixedStepSize(kc.DT)
    elif method == "rkm":
        manager.setIntegratorMethod(osim.Manager.IntegratorMethod_RungeKuttaMerson)
        manager.setIntegratorMaximumStepSize(kc.DT)
    else:
        raise ValueError(method)
    state.setTime(0.0)
    manager.initialize(state)
    t0 = time.perf_counter()
    final = manager.integrate(kc.DURATION)
    wall = time.perf_counter() - t0
    q = model.getCoordinateSet().get("knee_flexion").getValue(final)
    return wall, math.degrees(q)


def moment_arms(model: "osim.Model", muscles: list[kc.Muscle], angles_deg=(0.0, 45.0, 90.0)) -> dict:
    state = model.initSystem()
    coord = model.getCoordinateSet().get("knee_flexion")
    out = {}
    for m in muscles:
        path = osim.GeometryPath.safeDownCast(model.getMuscles().get(m.name).getPath())
        arms = []
        for a in angles_deg:
            coord.setValue(state, math.radians(a))
            model.realizePosition(state)
            arms.append(abs(path.computeMomentArm(state, coord)))
        out[m.name] = arms
    return out


def run(repeats: int) -> dict:
    osim.Logger.setLevelString("error")
    muscles = kc.load_muscles()
    t0 = time.perf_counter()
    model = build(muscles)
    model.initSystem()
    build_s = time.perf_counter() - t0
    res = {}
    for method in ("euler", "rkm"):
        best, angle = float("inf"), float("nan")
        for _ in range(repeats):
            wall, angle = simulate(model, method)
            best = min(best, wall)
        if not math.isfinite(angle):
            raise RuntimeError(f"simulation diverged ({method})")
        res[method] = (best, angle)
    arms = moment_arms(model, muscles)
    seconds, angle = res["euler"]
    steps = round(kc.DURATION / kc.DT)
    return {
        "name": "knee_hinge_16",
        "engine": f"OpenSim {osim.__version__}",
        "integrator": "ExplicitEuler, fixed 1 ms",
        "timestep": kc.DT,
        "steps": steps,
        "seconds": seconds,
        "per_unit_ns": seconds * 1e9 / steps,
        "unit": "ns per 1 ms step",
        "realtime_factor": kc.DURATION / seconds,
        "knee_angle_deg": angle,
        "seconds_rkmerson": res["rkm"][0],
        "realtime_factor_rkmerson": kc.DURATION / res["rkm"][0],
        "knee_angle_rkmerson_deg": res["rkm"][1],
        "build_seconds": build_s,
        "moment_arms_m_at_0_45_90_deg": {k: [round(v, 4) for v in a] for k, a in arms.items()},
        **kc.summary(muscles),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=kc.REPEATS)
    ap.add_argument("--print-osim", action="store_true", help="print the model as .osim XML and exit")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args()
    if a.print_osim:
        osim.Logger.setLevelString("error")
        model = build(kc.load_muscles())
        model.initSystem()
        print(model.dump())
        return
    r = run(a.repeats)
    if a.json:
        print(json.dumps(r))
        return
    print(f"{r['engine']}: one-DOF pin knee, {r['muscles']} DeGrooteFregly2016 muscles (rigid tendon); "
          f"defaulted: {', '.join(r['defaulted']) or 'none'}")
    print(f"  1 s simulated, best of {a.repeats}, {r['integrator']}: {r['seconds'] * 1e3:.1f} ms "
          f"({r['realtime_factor']:.1f} x realtime, {r['per_unit_ns'] / 1e3:.1f} us/step); knee at 1 s "
          f"{r['knee_angle_deg']:.1f} deg")
    print(f"  RungeKuttaMerson (accuracy default, max step 1 ms): {r['seconds_rkmerson'] * 1e3:.1f} ms "
          f"({r['realtime_factor_rkmerson']:.1f} x realtime); knee at 1 s "
          f"{r['knee_angle_rkmerson_deg']:.1f} deg")
    print("  moment arms (m) at 0 / 45 / 90 deg:")
    for k, v in r["moment_arms_m_at_0_45_90_deg"].items():
        print(f"    {k:<22} {v[0]:.4f} {v[1]:.4f} {v[2]:.4f}")


if __name__ == "__main__":
    main()
