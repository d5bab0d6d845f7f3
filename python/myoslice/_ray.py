"""Joining or starting Ray for sweeps and fits."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from types import ModuleType

#: Threads each run's Rust core may use: one task per CPU, so one thread each.
RUN_ENV = {"RAYON_NUM_THREADS": "1"}


def import_ray() -> ModuleType:
    """The ``ray`` module, or an ImportError saying how to get it."""
    try:
        import ray
    except ImportError as e:
        raise ImportError(
            "this needs Ray: pip install 'ray[tune]' pyarrow (sweeps also run without it: "
            "serial=True / --serial)"
        ) from e
    return ray


@contextmanager
def ray_session(address: str | None, workers: int | None) -> Iterator[ModuleType]:
    """Ray, connected: to the cluster at ``address``, or to a private local instance on the
    loopback interface with ``workers`` CPUs (default: all); shut down afterwards if this
    started it. An already connected Ray is used as it is."""
    ray = import_ray()
    started = False
    if not ray.is_initialized():
        common = {"log_to_driver": False, "runtime_env": {"env_vars": RUN_ENV}}
        if address is None:
            ray.init(
                num_cpus=workers or os.cpu_count() or 1,
                include_dashboard=False,
                _node_ip_address="127.0.0.1",
                **common,
            )
        else:
            ray.init(address=address, **common)
        started = True
    try:
        yield ray
    finally:
        if started:
            ray.shutdown()
