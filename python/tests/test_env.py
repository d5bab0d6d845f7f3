"""The Gymnasium environment ``myoslice/KneeReach-v0``."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

import myoslice  # noqa: E402
from myoslice import InvalidInputError, RendererUnavailableError, UnknownNameError  # noqa: E402
from myoslice.envs import KneeReach  # noqa: E402

ENV_ID = "myoslice/KneeReach-v0"


@pytest.fixture(scope="module")
def env() -> Iterator[Any]:
    """One environment for the module (each one builds a phantom)."""
    e = gymnasium.make(ENV_ID)
    yield e
    e.close()


def test_registered() -> None:
    assert myoslice.KNEE_REACH_ID == ENV_ID
    assert ENV_ID in gymnasium.registry
    assert gymnasium.spec(ENV_ID).entry_point == "myoslice.envs:KneeReach"


def test_registration_is_idempotent() -> None:
    import importlib

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # re-registering would warn "Overriding environment"
        importlib.reload(myoslice)
    assert ENV_ID in gymnasium.registry


def test_check_env(renderer_available: bool) -> None:
    env = gymnasium.make(ENV_ID).unwrapped
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            # Without a GPU adapter, rendering cannot be checked; everything else is.
            check_env(env, skip_render_check=not renderer_available)
    finally:
        env.close()


def test_spaces(env: Any) -> None:
    unwrapped: KneeReach = env.unwrapped
    n = len(unwrapped.muscle_names)
    assert env.action_space.shape == (n,)
    assert env.action_space.dtype == np.float32
    assert np.all(env.action_space.low == 0.0) and np.all(env.action_space.high == 1.0)
    assert env.observation_space.shape == (n + 3,)
    assert env.observation_space.dtype == np.float32
    assert np.all(np.isfinite(env.observation_space.low))
    assert np.all(np.isfinite(env.observation_space.high))


def test_default_muscles_are_the_knee_crossing_ones(env: Any) -> None:
    unwrapped: KneeReach = env.unwrapped
    sim = unwrapped.simulation
    expected = [m for m, g in zip(sim.muscle_names, sim.muscle_groups) if g in ("flexor", "extensor")]
    assert unwrapped.muscle_names == expected
    assert "semitendinosus" in expected and "vastus_lateralis" in expected


def test_seeded_reset_is_deterministic(env: Any) -> None:
    obs_1, info_1 = env.reset(seed=1)
    obs_2, info_2 = env.reset(seed=1)
    assert obs_1.dtype == np.float32
    assert np.array_equal(obs_1, obs_2)
    assert info_1 == info_2
    assert not np.shares_memory(obs_1, obs_2)
    obs_3, _ = env.reset(seed=2)
    assert obs_3[-1] != obs_1[-1]  # another target


def test_target_in_range(env: Any) -> None:
    lo, hi = math.radians(10.0), math.radians(120.0)
    for seed in range(20):
        obs, info = env.reset(seed=seed)
        assert lo <= info["target"] <= hi
        assert obs[-1] == np.float32(info["target"])


def test_random_steps(env: Any) -> None:
    obs, _ = env.reset(seed=3)
    env.action_space.seed(3)
    assert obs in env.observation_space
    unwrapped: KneeReach = env.unwrapped
    for _ in range(10):
        action = env.action_space.sample()
        obs, reward, terminated, truncated, info = env.step(action)
        assert isinstance(obs, np.ndarray) and obs.dtype == np.float32
        assert obs in env.observation_space
        assert isinstance(reward, float) and math.isfinite(reward)
        assert terminated is False and truncated is False
        a = np.clip(action.astype(np.float64), 0.0, 1.0)
        expected = -((info["knee_angle"] - info["target"]) ** 2) - unwrapped.effort_weight * float(np.mean(a * a))
        assert reward == pytest.approx(expected, rel=1e-12, abs=1e-12)
    assert info["time"] == pytest.approx(10 * unwrapped.control_dt)


def test_same_actions_same_trajectory(env: Any) -> None:
    rng = np.random.default_rng(0)
    actions = rng.uniform(0.0, 1.0, size=(8, env.action_space.shape[0])).astype(np.float32)

    def rollout() -> list[np.ndarray]:
        out = [env.reset(seed=5)[0]]
        out += [env.step(a)[0] for a in actions]
        return out

    for x, y in zip(rollout(), rollout()):
        assert np.array_equal(x, y)


def test_actions_are_clipped(env: Any) -> None:
    n = env.action_space.shape[0]
    env.reset(seed=4)
    over = env.step(np.full(n, 2.0, dtype=np.float32))
    env.reset(seed=4)
    full = env.step(np.ones(n, dtype=np.float32))
    assert np.array_equal(over[0], full[0])
    assert over[1] == full[1]


def test_bad_actions(env: Any) -> None:
    n = env.action_space.shape[0]
    env.reset(seed=0)
    unwrapped = env.unwrapped
    with pytest.raises(InvalidInputError):
        unwrapped.step(np.zeros(n + 1, dtype=np.float32))
    with pytest.raises(InvalidInputError):
        unwrapped.step(np.full(n, np.nan, dtype=np.float32))


def test_flexors_raise_the_knee(env: Any) -> None:
    unwrapped: KneeReach = env.unwrapped
    groups = dict(zip(unwrapped.simulation.muscle_names, unwrapped.simulation.muscle_groups))
    action = np.array([groups[m] == "flexor" for m in unwrapped.muscle_names], dtype=np.float32)
    obs, _ = env.reset(seed=0)
    for _ in range(25):  # 0.5 s
        obs, *_ = env.step(action)
    assert obs[0] > 0.5


def test_compliant_tendons_reach_the_policy_through_the_simulation() -> None:
    env = KneeReach(tendon="compliant", muscles=["semitendinosus", "biceps_femoris_long"])
    try:
        assert env.simulation.tendon == "compliant"
        obs, _ = env.reset(seed=0)
        for _ in range(25):  # 0.5 s of both flexors at full excitation
            obs, *_ = env.step(np.ones(2, dtype=np.float32))
        assert obs[0] > 0.3 and obs in env.observation_space
    finally:
        env.close()


def test_episode_is_truncated_on_time() -> None:
    env = gymnasium.make(ENV_ID, episode_seconds=0.1, control_dt=0.02)
    try:
        env.reset(seed=0)
        zero = np.zeros(env.action_space.shape, dtype=np.float32)
        for i in range(5):
            _, _, terminated, truncated, info = env.step(zero)
            assert terminated is False
            assert truncated is (i == 4)
        assert info["time"] == pytest.approx(0.1)
    finally:
        env.close()


def test_reset_option_sets_the_target(env: Any) -> None:
    obs, info = env.reset(seed=0, options={"target": 1.25})
    assert info["target"] == 1.25 and obs[-1] == np.float32(1.25)
    with pytest.raises(InvalidInputError):
        env.reset(options={"target": 5.0})


def test_custom_muscles_and_bad_options() -> None:
    env = KneeReach(muscles=["semitendinosus", "vastus_lateralis"], control_dt=0.01)
    try:
        assert env.action_space.shape == (2,)
        assert env.observation_space.shape == (5,)
        obs, _ = env.reset(seed=0)
        obs, *_ = env.step(np.array([1.0, 0.0], dtype=np.float32))
        assert obs in env.observation_space
    finally:
        env.close()
    with pytest.raises(UnknownNameError) as info:
        KneeReach(muscles=["semitendinosis"])
    assert "did you mean" in str(info.value)
    bad: list[dict[str, Any]] = [
        {"control_dt": 0.0},
        {"control_dt": 0.0125},
        {"episode_seconds": -1.0},
        {"effort_weight": math.nan},
        {"target_range_deg": (90.0, 10.0)},
        {"muscles": []},
        {"tendon": "elastic"},
    ]
    for kwargs in bad:
        with pytest.raises(InvalidInputError):
            KneeReach(**kwargs)
    with pytest.raises(InvalidInputError):
        KneeReach(render_mode="human")


def test_render_rgb_array() -> None:
    env = gymnasium.make(ENV_ID, render_mode="rgb_array")
    try:
        env.reset(seed=0)
        try:
            frame = env.render()
        except RendererUnavailableError as e:
            assert "render" in str(e)
            return
        width, height = env.unwrapped.render_size
        assert isinstance(frame, np.ndarray)
        assert frame.dtype == np.uint8
        assert frame.shape == (height, width, 3)
        assert frame.max() > frame.min()  # not a blank image
    finally:
        env.close()


def test_render_without_mode_returns_none(env: Any) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert env.unwrapped.render() is None


def test_close_is_idempotent() -> None:
    env = gymnasium.make(ENV_ID)
    env.reset(seed=0)
    env.close()
    env.close()
    with pytest.raises(gymnasium.error.ClosedEnvironmentError):
        env.unwrapped.step(np.zeros(env.action_space.shape, dtype=np.float32))


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_runs_the_same_episodes_as_single_envs(mode: str) -> None:
    """``gymnasium.make_vec`` works in both modes (async forks worker processes, whose
    parallel loops get threads of their own) and each sub-environment follows the
    single environment step for step."""
    actions = np.full((3, 2, 13), 0.4, dtype=np.float32)
    actions[:, 1] = 0.1
    vec = gymnasium.make_vec(ENV_ID, num_envs=2, vectorization_mode=mode)
    try:
        obs, _ = vec.reset(seed=[5, 6])
        seen = [obs]
        for a in actions:
            obs, _, _, _, _ = vec.step(a)
            seen.append(obs)
    finally:
        vec.close()
    for i, seed in enumerate((5, 6)):
        env = gymnasium.make(ENV_ID)
        try:
            o, _ = env.reset(seed=seed)
            mine = [o]
            for a in actions:
                o, _, _, _, _ = env.step(a[i])
                mine.append(o)
        finally:
            env.close()
        np.testing.assert_array_equal(np.array([s[i] for s in seen]), np.array(mine))
