"""Exceptions raised by myoslice.

Every error is a :class:`MyoSliceError`, so ``except myoslice.MyoSliceError`` catches
all of them. Each also derives from the built-in exception a Python user would expect,
so ordinary handlers keep working:

================================  ====================================================
class                             raised for
================================  ====================================================
:class:`InvalidInputError`        a bad number (NaN, out of range, ``dt <= 0``), a wrong
                                  array shape, an unknown option value
                                  (also a :class:`ValueError`)
:class:`UnknownNameError`         an unknown muscle or group name; the message suggests
                                  the closest known name ("did you mean ...")
                                  (also an :class:`InvalidInputError` and a :class:`KeyError`)
:class:`ModelFileError`           a missing, unreadable or malformed volume, label table
                                  or scenario file (also an :class:`OSError`)
:class:`SimulationError`          the simulation became non-finite; the last good state
                                  is kept (also a :class:`RuntimeError`)
:class:`RendererUnavailableError` no GPU adapter for off-screen rendering
                                  (also a :class:`RuntimeError`)
================================  ====================================================

This module is pure Python and must not import the compiled module: the compiled module
imports it to raise these classes.
"""

from __future__ import annotations

__all__ = [
    "InvalidInputError",
    "ModelFileError",
    "MyoSliceError",
    "RendererUnavailableError",
    "SimulationError",
    "UnknownNameError",
]


class MyoSliceError(Exception):
    """Base class of every error raised by myoslice."""


class InvalidInputError(MyoSliceError, ValueError):
    """A bad input value: NaN, out of range, negative step, wrong shape, unknown option."""


class UnknownNameError(InvalidInputError, KeyError):
    """An unknown muscle or group name. The message suggests the closest known name."""

    def __str__(self) -> str:
        # KeyError.__str__ would print repr() of the message, quotes included.
        if len(self.args) == 1:
            return str(self.args[0])
        return Exception.__str__(self)


class ModelFileError(MyoSliceError, OSError):
    """A model, label table or scenario file is missing, unreadable or malformed."""


class SimulationError(MyoSliceError, RuntimeError):
    """The simulation became non-finite. The state before the failing call is kept."""


class RendererUnavailableError(MyoSliceError, RuntimeError):
    """Off-screen rendering is not possible here (no GPU adapter, or no renderer built)."""
