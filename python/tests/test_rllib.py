"""RLlib's PPO learns on ``KneeReach`` (``python/examples/rllib_ppo.py``): the mean
episode return rises over a short training run.

RLlib pins an older gymnasium than the other tests use, so ``scripts/test.sh`` runs this
file in an environment of its own (``python/requirements-rllib.txt``) with
``MYOSLICE_REQUIRE_RLLIB=1``, where a missing RLlib fails instead of skipping."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

if os.environ.get("MYOSLICE_REQUIRE_RLLIB") != "1":
    pytest.importorskip("ray.rllib", reason="RLlib runs in its own environment (scripts/test.sh)")
    pytest.importorskip("torch", reason="RLlib runs in its own environment (scripts/test.sh)")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rllib_ppo.py"


def test_ppo_raises_the_mean_return_on_knee_reach() -> None:
    spec = importlib.util.spec_from_file_location("rllib_ppo", EXAMPLE)
    assert spec is not None and spec.loader is not None
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    returns = example.train(iterations=15, env_runners=1, seed=0)
    assert len(returns) == 15 and np.all(np.isfinite(returns)), returns
    first, last = np.mean(returns[:3]), np.mean(returns[-3:])
    assert last > first + 2.0, returns
