"""A hand-written PID controller on ``myoslice/KneeReach-v0`` (no learning library).

The knee-angle error drives the flexors when the knee must bend further and the
extensors when it must straighten; an integral term learns the load of the shank.

    python examples/controller.py [--episodes 5] [--seed 0]

Prints the mean absolute error of each episode, next to doing nothing.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import gymnasium
import numpy as np
import numpy.typing as npt

import myoslice
from myoslice.envs import KneeReach


class PidController:
    """Excitations from the knee-angle error: ``u = kp*e + ki*integral(e) - kd*velocity``,
    positive ``u`` to the flexors, negative ``u`` to the extensors, plus an optional
    co-contraction of both. Gains are per radian (and per rad/s, rad s)."""

    def __init__(
        self,
        flexor: npt.NDArray[np.bool_],
        dt: float,
        kp: float = 5.0,
        ki: float = 10.0,
        kd: float = 0.3,
        co_contraction: float = 0.0,
    ) -> None:
        self.flexor = flexor
        self.dt = dt
        self.kp, self.ki, self.kd = kp, ki, kd
        self.co_contraction = co_contraction
        self.integral = 0.0

    def reset(self) -> None:
        self.integral = 0.0

    def __call__(self, angle: float, velocity: float, target: float) -> npt.NDArray[np.float32]:
        error = target - angle
        u = self.kp * error + self.ki * self.integral - self.kd * velocity
        # Integrate only while the command is not saturated (anti-windup).
        if abs(u) < 1.0:
            self.integral += error * self.dt
        flex = np.clip(u, 0.0, 1.0) + self.co_contraction
        extend = np.clip(-u, 0.0, 1.0) + self.co_contraction
        action: npt.NDArray[np.float32] = np.where(self.flexor, flex, extend).clip(0.0, 1.0).astype(np.float32)
        return action


def run_episode(
    env: gymnasium.Env[npt.NDArray[np.float32], npt.NDArray[np.float32]],
    seed: int,
    controller: PidController | None,
) -> tuple[float, float, float]:
    """Runs one episode; returns (target, mean |error|, final |error|) in radians."""
    obs, info = env.reset(seed=seed)
    if controller is not None:
        controller.reset()
    zero = np.zeros_like(env.action_space.sample())
    errors = []
    while True:
        angle, velocity, target = float(obs[0]), float(obs[1]), float(obs[-1])
        action = zero if controller is None else controller(angle, velocity, target)
        obs, _, terminated, truncated, info = env.step(action)
        errors.append(info["abs_error"])
        if terminated or truncated:
            return info["target"], float(np.mean(errors)), errors[-1]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    t0 = time.perf_counter()
    env = gymnasium.make(myoslice.KNEE_REACH_ID)
    knee: KneeReach = env.unwrapped  # type: ignore[assignment]
    groups = dict(zip(knee.simulation.muscle_names, knee.simulation.muscle_groups))
    flexor = np.array([groups[m] == "flexor" for m in knee.muscle_names])
    controller = PidController(flexor, dt=knee.control_dt)
    print(f"{len(knee.muscle_names)} muscles ({int(flexor.sum())} flexors), episodes of {knee.episode_seconds:g} s")
    print(f"{'episode':>7} {'target':>8} {'PID mean|err|':>14} {'final|err|':>11} {'idle mean|err|':>15}")

    pid_errors, idle_errors = [], []
    for episode in range(args.episodes):
        seed = args.seed + episode
        target, mean_error, final_error = run_episode(env, seed, controller)
        _, idle_error, _ = run_episode(env, seed, None)
        pid_errors.append(mean_error)
        idle_errors.append(idle_error)
        print(
            f"{episode:7d} {math.degrees(target):7.1f}° {math.degrees(mean_error):13.1f}° "
            f"{math.degrees(final_error):10.1f}° {math.degrees(idle_error):14.1f}°"
        )
    env.close()
    print(
        f"mean over {args.episodes} episodes: PID {math.degrees(float(np.mean(pid_errors))):.1f}°, "
        f"idle {math.degrees(float(np.mean(idle_errors))):.1f}° ({time.perf_counter() - t0:.1f} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
