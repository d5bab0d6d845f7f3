"""Training a policy on ``KneeReach`` with RLlib's PPO (Ray's reinforcement learning).

    python examples/rllib_ppo.py [--iterations 8] [--env-runners 1] [--seed 0]

Prints the mean episode return of each training iteration; it rises as the policy
learns to bring the knee to its target. Needs ``ray[rllib]`` and torch (RLlib pins its
own gymnasium version: a separate environment is simplest, see docs/sweeps.md).
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

import numpy as np


def train(iterations: int, env_runners: int, seed: int) -> list[float]:
    """Trains PPO and returns each iteration's mean episode return."""
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    from myoslice.envs import KneeReach

    def make(cfg: dict[str, Any]) -> KneeReach:
        return KneeReach(**cfg)

    register_env("myoslice-knee-reach", make)
    config = (
        PPOConfig()  # type: ignore[no-untyped-call]
        .environment(
            "myoslice-knee-reach",
            # One second episodes of 25 decisions toward targets of 50-70 deg: a task a
            # policy learns in minutes on two CPUs (the full 10-120 deg range takes hours).
            env_config={
                "episode_seconds": 1.0,
                "control_dt": 0.04,
                "target_range_deg": (50.0, 70.0),
            },
        )
        .env_runners(num_env_runners=env_runners, num_envs_per_env_runner=4,
                     rollout_fragment_length=200 if env_runners == 0 else "auto")
        .training(
            train_batch_size_per_learner=800,
            minibatch_size=200,
            num_epochs=6,
            lr=1e-3,
            gamma=0.95,
        )
        .debugging(seed=seed)
    )
    started = not ray.is_initialized()
    if started:
        ray.init(num_cpus=max(2, env_runners + 1), include_dashboard=False,
                 _node_ip_address="127.0.0.1", log_to_driver=False)
    try:
        algo: Any = config.build_algo()
        returns = []
        for i in range(iterations):
            result = algo.train()
            r = float(result["env_runners"].get("episode_return_mean", math.nan))
            returns.append(r)
            print(f"iteration {i + 1:2d}: mean episode return {r:8.3f}", flush=True)
        algo.stop()
    finally:
        if started:
            ray.shutdown()
    return returns


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--iterations", type=int, default=8)
    ap.add_argument("--env-runners", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    returns = train(args.iterations, args.env_runners, args.seed)
    first, last = np.nanmean(returns[:2]), np.nanmean(returns[-2:])
    print(f"mean return, first two iterations {first:.3f}, last two {last:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
