"""``python -m myoslice``: the Python side of the ``myoslice`` command (sweeps, fits)."""

from .cli import main

raise SystemExit(main())
