"""``KneeReach``: bring the knee to a random target angle with the muscles that cross it."""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence
from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt

try:
    import gymnasium
    from gymnasium import spaces
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError(
        "myoslice.envs needs gymnasium: pip install gymnasium (or the 'gym' extra of myoslice)"
    ) from e

from .._myoslice import Simulation, State
from ..errors import InvalidInputError, RendererUnavailableError, UnknownNameError

__all__ = ["KneeReach"]

#: Simulation step of the environment (s): ``control_dt`` is a whole number of these.
SIM_DT = 0.001

# Observation bounds: knee angle (rad), knee velocity (rad/s), activation, target (rad).
_ANGLE_BOUNDS = (-0.5, 3.0)
_VELOCITY_BOUNDS = (-50.0, 50.0)
_TARGET_BOUNDS = (0.0, 3.0)

Obs: TypeAlias = npt.NDArray[np.float32]
Action: TypeAlias = npt.NDArray[np.float32]


class KneeReach(gymnasium.Env[Obs, Action]):
    """Reach a random knee flexion angle with the knee-crossing muscles of the phantom leg.

    Each episode draws a target angle uniformly from ``target_range_deg`` and lasts
    ``episode_seconds`` of simulated time, in control steps of ``control_dt``.

    **Action**: ``Box(0, 1, (n,), float32)``, the excitations of the controlled muscles
    (:attr:`muscle_names`; by default every muscle of group ``"flexor"`` or
    ``"extensor"``, in the simulation's order). Values outside [0, 1] are clipped; the
    muscles not controlled keep an excitation of 0.

    **Observation**: ``Box(float32)`` of ``[knee_angle, knee_velocity, activation of each
    controlled muscle..., target_angle]``, angles in rad, velocity in rad/s, each clipped
    to the space's bounds (angle [-0.5, 3], velocity [-50, 50], activation [0, 1],
    target [0, 3]).

    **Reward**: ``-(knee_angle - target)**2 - effort_weight * mean(action**2)``.

    **Episode end**: never terminated; truncated once ``episode_seconds`` have elapsed.

    ``reset(options={"target": angle_rad})`` sets the target instead of drawing it.
    ``render_mode="rgb_array"`` makes :meth:`render` return a ``(H, W, 3)`` uint8 image
    from the GPU renderer (:class:`~myoslice.errors.RendererUnavailableError` without one).

    The phantom is built once in ``__init__`` (about 2 s); ``reset`` restores a saved
    checkpoint of its initial state, so resets are cheap and bit-for-bit repeatable.
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        target_range_deg: tuple[float, float] = (10.0, 120.0),
        episode_seconds: float = 2.0,
        control_dt: float = 0.02,
        effort_weight: float = 0.01,
        tissue: bool = False,
        tendon: str = "rigid",
        muscles: Sequence[str] | None = None,
        render_size: tuple[int, int] = (480, 360),
        camera: str = "side",
    ) -> None:
        """
        Args:
            render_mode: ``None`` or ``"rgb_array"``.
            target_range_deg: range the target flexion angle is drawn from (degrees).
            episode_seconds: simulated time per episode (s).
            control_dt: time between actions (s), a whole number of 1 ms steps.
            effort_weight: weight of the mean squared excitation in the reward.
            tissue: also simulate the deformable tissue (slower; only matters for
                rendering and the tissue metrics of :attr:`simulation`).
            tendon: ``"rigid"`` or ``"compliant"`` (elastic tendons: the fibre lengths
                become states the policy cannot see directly).
            muscles: names of the controlled muscles; default: the knee flexors and
                extensors.
            render_size: ``(width, height)`` of rendered frames (pixels).
            camera: camera preset of rendered frames (``"side"``, ``"front"``, ``"back"``,
                ``"medial"`` or ``"oblique"``).
        """
        super().__init__()
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise InvalidInputError(
                f"render_mode = {render_mode!r}: expected None or one of {self.metadata['render_modes']}"
            )
        self.render_mode = render_mode

        lo_deg, hi_deg = (float(v) for v in target_range_deg)
        max_deg = math.degrees(_TARGET_BOUNDS[1])
        if not (math.isfinite(lo_deg) and math.isfinite(hi_deg) and 0.0 <= lo_deg <= hi_deg <= max_deg):
            raise InvalidInputError(
                f"target_range_deg = {target_range_deg!r}: expected 0 <= low <= high <= {max_deg:.1f}"
            )
        if not (math.isfinite(episode_seconds) and episode_seconds > 0.0):
            raise InvalidInputError(f"episode_seconds = {episode_seconds}: expected a finite duration > 0 s")
        substeps = round(control_dt / SIM_DT) if math.isfinite(control_dt) else 0
        if substeps < 1 or abs(substeps * SIM_DT - control_dt) > 1e-9:
            raise InvalidInputError(
                f"control_dt = {control_dt}: expected a positive multiple of {SIM_DT} s"
            )
        if not (math.isfinite(effort_weight) and effort_weight >= 0.0):
            raise InvalidInputError(f"effort_weight = {effort_weight}: expected a finite value >= 0")
        width, height = (int(v) for v in render_size)
        if muscles is not None and len(muscles) == 0:
            raise InvalidInputError("muscles = []: expected at least one muscle (or None for the default)")

        self._sim: Simulation | None = Simulation.phantom(tissue=tissue, tendon=tendon)
        sim = self._sim
        names = sim.muscle_names
        if muscles is None:
            chosen = [n for n, g in zip(names, sim.muscle_groups) if g in ("flexor", "extensor")]
        else:
            chosen = list(muscles)
            for name in chosen:
                if name not in names:
                    close = difflib.get_close_matches(name, names, n=1)
                    hint = f" (did you mean '{close[0]}'?)" if close else ""
                    raise UnknownNameError(f"unknown muscle '{name}'{hint}")
            if len(set(chosen)) != len(chosen):
                raise InvalidInputError(f"muscles = {chosen!r}: each muscle may appear only once")

        lo_rad, hi_rad = sim.knee_limits
        if math.radians(lo_deg) < lo_rad or math.radians(hi_deg) > hi_rad:
            raise InvalidInputError(
                f"target_range_deg = {target_range_deg!r}: outside the knee's range "
                f"[{math.degrees(lo_rad):.1f}, {math.degrees(hi_rad):.1f}] deg"
            )

        self.muscle_names: list[str] = chosen
        """Names of the controlled muscles, in action order."""
        self.target_range: tuple[float, float] = (math.radians(lo_deg), math.radians(hi_deg))
        """Range the target is drawn from (rad)."""
        self.episode_seconds = float(episode_seconds)
        self.control_dt = float(control_dt)
        self.effort_weight = float(effort_weight)
        self.render_size = (width, height)
        self.camera = camera
        self._color = "area" if tissue else "none"
        self._substeps = substeps
        self._max_steps = max(1, round(episode_seconds / control_dt))
        self._index = np.array([names.index(n) for n in chosen], dtype=np.intp)
        self._excitations = np.zeros(len(names), dtype=np.float64)
        self._initial: State = sim.state()
        self._steps = 0
        self.target: float = self.target_range[0]
        """Target knee flexion of the current episode (rad)."""

        n = len(chosen)
        self.action_space = spaces.Box(0.0, 1.0, shape=(n,), dtype=np.float32)
        low = np.concatenate(
            ([_ANGLE_BOUNDS[0], _VELOCITY_BOUNDS[0]], np.zeros(n), [_TARGET_BOUNDS[0]])
        ).astype(np.float32)
        high = np.concatenate(
            ([_ANGLE_BOUNDS[1], _VELOCITY_BOUNDS[1]], np.ones(n), [_TARGET_BOUNDS[1]])
        ).astype(np.float32)
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        self._low, self._high = low, high

    @property
    def simulation(self) -> Simulation:
        """The underlying simulation (read its muscles, tissue, surfaces...)."""
        return self._live()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Obs, dict[str, Any]]:
        """Restores the initial pose and draws a new target (``options={"target": rad}``
        sets it instead)."""
        super().reset(seed=seed)
        sim = self._live()
        sim.set_state(self._initial)
        self._excitations[:] = 0.0
        sim.set_excitations(self._excitations)
        self._steps = 0
        target = None if options is None else options.get("target")
        if target is None:
            self.target = float(self.np_random.uniform(*self.target_range))
        else:
            t = float(target)
            if not (math.isfinite(t) and _TARGET_BOUNDS[0] <= t <= _TARGET_BOUNDS[1]):
                raise InvalidInputError(
                    f"options['target'] = {target!r}: expected an angle in "
                    f"[{_TARGET_BOUNDS[0]}, {_TARGET_BOUNDS[1]}] rad"
                )
            self.target = t
        return self._observation(sim), self._info(sim)

    def step(self, action: Action) -> tuple[Obs, float, bool, bool, dict[str, Any]]:
        """Applies the excitations for ``control_dt`` seconds."""
        sim = self._live()
        a = np.asarray(action, dtype=np.float64)
        if a.shape != self.action_space.shape:
            raise InvalidInputError(
                f"action of shape {a.shape}: expected {self.action_space.shape} "
                f"(one excitation per muscle of {self.muscle_names})"
            )
        if not np.all(np.isfinite(a)):
            raise InvalidInputError(f"action {a}: expected finite excitations")
        a = np.clip(a, 0.0, 1.0)
        self._excitations[self._index] = a
        sim.set_excitations(self._excitations)
        sim.step(SIM_DT, n=self._substeps)
        self._steps += 1
        error = sim.knee_angle - self.target
        reward = -(error**2) - self.effort_weight * float(np.mean(a * a))
        truncated = self._steps >= self._max_steps
        return self._observation(sim), float(reward), False, truncated, self._info(sim)

    def render(self) -> npt.NDArray[np.uint8] | None:
        """The current frame as ``(height, width, 3)`` uint8 when ``render_mode ==
        "rgb_array"``; ``None`` (with a warning) without a render mode."""
        if self.render_mode is None:
            gymnasium.logger.warn(
                "KneeReach.render() called without a render mode: "
                'create the env with render_mode="rgb_array"'
            )
            return None
        sim = self._live()
        width, height = self.render_size
        try:
            return sim.render(width, height, color=self._color, camera=self.camera)
        except RendererUnavailableError as e:
            raise RendererUnavailableError(
                f"KneeReach cannot render: {e}. Use render_mode=None to run without a GPU."
            ) from e

    def close(self) -> None:
        """Releases the simulation. Calling it again does nothing."""
        self._sim = None

    def _live(self) -> Simulation:
        if self._sim is None:
            raise gymnasium.error.ClosedEnvironmentError("KneeReach is closed")
        return self._sim

    def _observation(self, sim: Simulation) -> Obs:
        n = len(self.muscle_names)
        obs = np.empty(n + 3, dtype=np.float32)  # fresh every call: callers may keep it
        obs[0] = sim.knee_angle
        obs[1] = sim.knee_velocity
        obs[2 : 2 + n] = sim.activations[self._index]
        obs[-1] = self.target
        return np.clip(obs, self._low, self._high, out=obs)

    def _info(self, sim: Simulation) -> dict[str, Any]:
        return {
            "time": sim.time - self._initial.time,
            "knee_angle": sim.knee_angle,
            "target": self.target,
            "abs_error": abs(sim.knee_angle - self.target),
        }
