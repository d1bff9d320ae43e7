"""sigcore's MuJoCo physics backend (the default): registers :class:`MujocoBackend` as ``"mujoco"``."""

from __future__ import annotations

from collections.abc import Callable

from sigcore.backend import Backend
from sigcore.plugins import hookimpl

from .backend import MujocoBackend

__all__ = ["MujocoBackend", "sigcore_register_backends"]


@hookimpl
def sigcore_register_backends(register: Callable[[type[Backend]], None]) -> None:
    """Register the MuJoCo backend under the name ``"mujoco"``."""
    register(MujocoBackend)
