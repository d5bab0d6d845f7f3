"""Shared fixtures. Building the phantom takes about 2 s, so each flavour (rigid, with
tissue) is built once per session and tests get it back at its initial state through
``state()`` / ``set_state()`` instead of rebuilding."""

from __future__ import annotations

import os
from collections.abc import Iterator

import numpy as np
import pytest

try:
    from myoslice import Simulation, State
except ImportError as e:  # pragma: no cover - setup problem
    raise pytest.UsageError(
        f"cannot import myoslice ({e}). Install it first (`pip install ./python` or "
        "`cd python && maturin develop`), and run pytest from the repository root so that "
        "the source folder python/myoslice (without the compiled module) does not shadow it."
    ) from e

# Ray (sweeps, fits) on this machine's loopback interface only: Ray's switch for machines
# that are not cluster hosts, which makes every node, the test cluster's too, use
# 127.0.0.1. Set before Ray is imported.
os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")


def _restored(built: tuple[Simulation, State]) -> Simulation:
    sim, initial = built
    sim.set_state(initial)
    sim.set_excitations(np.zeros(len(sim.muscle_names)))
    return sim


@pytest.fixture(scope="session")
def rigid_built() -> tuple[Simulation, State]:
    """The phantom without tissue, and its initial checkpoint."""
    sim = Simulation.phantom(tissue=False)
    return sim, sim.state()


@pytest.fixture(scope="session")
def tissue_built() -> tuple[Simulation, State]:
    """The phantom with tissue, and its initial checkpoint."""
    sim = Simulation.phantom(tissue=True)
    return sim, sim.state()


@pytest.fixture
def rigid(rigid_built: tuple[Simulation, State]) -> Iterator[Simulation]:
    """The rigid phantom at rest (t = 0, every excitation 0)."""
    yield _restored(rigid_built)


@pytest.fixture
def tissue(tissue_built: tuple[Simulation, State]) -> Iterator[Simulation]:
    """The phantom with tissue at rest (t = 0, every excitation 0)."""
    yield _restored(tissue_built)


@pytest.fixture(scope="session")
def renderer_available(rigid_built: tuple[Simulation, State]) -> bool:
    """Whether this machine can render off-screen (a GPU or software adapter)."""
    from myoslice import RendererUnavailableError

    try:
        rigid_built[0].render(32, 32)
    except RendererUnavailableError:
        return False
    return True
