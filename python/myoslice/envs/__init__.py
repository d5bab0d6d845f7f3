"""Gymnasium environments of myoslice (needs ``gymnasium``).

``import myoslice`` registers them when gymnasium is installed:

==========================  ===========================================================
id                          class
==========================  ===========================================================
``myoslice/KneeReach-v0``   :class:`KneeReach`: reach a random knee angle with the
                            knee flexors and extensors
==========================  ===========================================================
"""

from __future__ import annotations

from .knee_reach import KneeReach

__all__ = ["KneeReach"]
