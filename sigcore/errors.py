"""The root of every sigcore exception.

Each subpackage keeps its own errors in its ``exceptions.py`` (``sigcore.world.WorldError``,
``sigcore.agent.ApiError``, ``sigcore.sim.SimulationError``, ...) and the bundled plugins in theirs; every one of them
derives from :class:`SigcoreError`, and also from the built-in class that code already catches (``ApiError`` is a
``ValueError``, ``PluginError`` a ``LookupError``, ``BackendError`` a ``RuntimeError``).
"""

from __future__ import annotations


class SigcoreError(Exception):
    """Base class of every error sigcore and its bundled plugins raise on purpose (catch this to catch them all)."""
