"""Errors of the simulation."""

from __future__ import annotations


class SimulationError(RuntimeError):
    """The simulation cannot do what was asked (e.g. build a world, or step after it was closed)."""
