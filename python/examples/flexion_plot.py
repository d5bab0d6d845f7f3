"""Knee flexion by the hamstrings (the paper's experiment), plotted.

The four hamstrings (semitendinosus, semimembranosus, long and short heads of biceps
femoris) are fully excited from rest; the script records the knee angle and their tendon
forces and writes a two-panel figure.

    python examples/flexion_plot.py [out.png] [--seconds 1.0] [--tissue]

Needs matplotlib (``pip install matplotlib``).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import matplotlib

if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.environ.get("MPLBACKEND")):
    matplotlib.use("Agg")  # no display: draw off-screen

import matplotlib.pyplot as plt
import numpy as np

import myoslice

HAMSTRINGS = ("semitendinosus", "semimembranosus", "biceps_femoris_long", "biceps_femoris_short")
DT = 0.001  # simulation step (s)
RECORD_EVERY = 5  # steps between samples


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", nargs="?", default="flexion.png", type=Path, help="output image (default ./flexion.png)")
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated time (default 1 s)")
    parser.add_argument("--excitation", type=float, default=1.0, help="hamstring excitation in [0, 1]")
    parser.add_argument("--tissue", action="store_true", help="also simulate the deformable tissue (slower)")
    args = parser.parse_args(argv)

    t0 = time.perf_counter()
    sim = myoslice.Simulation.phantom(tissue=args.tissue)
    built = time.perf_counter() - t0
    names = sim.muscle_names
    index = [names.index(m) for m in HAMSTRINGS]

    sim.set_excitations(dict.fromkeys(HAMSTRINGS, args.excitation))
    samples = max(1, round(args.seconds / (DT * RECORD_EVERY)))
    times = np.empty(samples + 1)
    angles = np.empty(samples + 1)
    forces = np.empty((samples + 1, len(HAMSTRINGS)))

    def record(k: int) -> None:
        times[k] = sim.time
        angles[k] = sim.knee_angle
        forces[k] = sim.forces[index]

    record(0)
    t0 = time.perf_counter()
    for k in range(1, samples + 1):
        sim.step(DT, n=RECORD_EVERY)
        record(k)
    ran = time.perf_counter() - t0

    fig, (ax_angle, ax_force) = plt.subplots(2, 1, sharex=True, figsize=(7, 6), constrained_layout=True)
    ax_angle.plot(times, np.degrees(angles), color="tab:blue")
    ax_angle.set_ylabel("knee flexion (deg)")
    ax_angle.set_title(f"Knee flexion by the hamstrings (excitation {args.excitation:g})")
    ax_angle.grid(alpha=0.3)
    for j, name in enumerate(HAMSTRINGS):
        ax_force.plot(times, forces[:, j], label=name.replace("_", " "))
    ax_force.set_xlabel("time (s)")
    ax_force.set_ylabel("tendon force (N)")
    ax_force.legend(loc="best", fontsize="small")
    ax_force.grid(alpha=0.3)
    fig.savefig(args.out, dpi=120)
    plt.close(fig)

    print(f"built the phantom in {built:.2f} s; simulated {sim.time:.3f} s in {ran:.2f} s")
    print(f"knee flexion: {math.degrees(angles[-1]):.1f} deg (peak {math.degrees(float(angles.max())):.1f} deg)")
    for j, name in enumerate(HAMSTRINGS):
        print(f"  {name:22s} peak force {forces[:, j].max():8.1f} N")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
