"""myoslice: a deformable human lower limb built from labelled anatomical slices and
moved by its own muscles.

The simulation runs in Rust; this package exposes it with numpy arrays. Units are SI
(metres, seconds, newtons, radians).

Example::

    import myoslice

    sim = myoslice.Simulation.phantom(tissue=False)      # built-in leg, ~2 s to build
    sim.set_excitations({"semitendinosus": 1.0, "biceps_femoris_long": 1.0})
    sim.step(0.001, n=500)                                 # 0.5 s of simulated time
    print(f"knee flexion {sim.knee_angle:.2f} rad")
    print(dict(zip(sim.muscle_names, sim.forces)))         # tendon forces (N)

    checkpoint = sim.state()                               # cheap snapshots
    sim.step(0.001, n=100)
    sim.set_state(checkpoint)                              # bit-identical replay

With gymnasium installed, the reaching task is registered as ``"myoslice/KneeReach-v0"``::

    import gymnasium, myoslice
    env = gymnasium.make("myoslice/KneeReach-v0")

Scenario files run with :func:`run_scenario` (as ``myoslice run`` does); many runs at once
with :func:`myoslice.sweep.sweep` (on Ray), and muscle parameters fitted to a measured
knee trajectory with :func:`myoslice.fit.fit` (Ray Tune).

Errors all derive from :class:`MyoSliceError` (see :mod:`myoslice.errors`).
"""

from __future__ import annotations

from ._myoslice import Simulation, State, __version__, check_scenario, run_scenario
from .errors import (
    InvalidInputError,
    ModelFileError,
    MyoSliceError,
    RendererUnavailableError,
    SimulationError,
    UnknownNameError,
)

__all__ = [
    "KNEE_REACH_ID",
    "InvalidInputError",
    "ModelFileError",
    "MyoSliceError",
    "RendererUnavailableError",
    "Simulation",
    "SimulationError",
    "State",
    "UnknownNameError",
    "__version__",
    "check_scenario",
    "run_scenario",
]

#: Gymnasium id of :class:`myoslice.envs.KneeReach`.
KNEE_REACH_ID = "myoslice/KneeReach-v0"


def _register_envs() -> None:
    """Registers the Gymnasium environments when gymnasium is installed (it is optional)."""
    try:
        import gymnasium
    except ImportError:
        return
    if KNEE_REACH_ID not in gymnasium.registry:
        gymnasium.register(id=KNEE_REACH_ID, entry_point="myoslice.envs:KneeReach")


_register_envs()
