"""sigcore's PyBullet physics backend: registers :class:`BulletBackend` as ``"bullet"``."""

from __future__ import annotations

from collections.abc import Callable

from sigcore.backend import Backend
from sigcore.plugins import hookimpl

from ._quiet import import_pybullet

import_pybullet()

from .backend import BulletBackend  # noqa: E402

__all__ = ["BulletBackend", "sigcore_register_backends"]


@hookimpl
def sigcore_register_backends(register: Callable[[type[Backend]], None]) -> None:
    """Register the PyBullet backend under the name ``"bullet"``."""
    register(BulletBackend)
