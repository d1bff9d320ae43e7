"""sigcore-hello: the example plugin of ``docs/plugins.md``.

This module is the entry point (``[project.entry-points.sigcore] hello = "sigcore_hello"``): sigcore registers
it with pluggy and calls the ``@sigcore.hookimpl`` functions below, each handing over a ``register`` callback.
"""

from __future__ import annotations

from collections.abc import Callable

import sigcore
from sigcore.agent import Controller
from sigcore.feature import Feature

from .feature import HelloFeature
from .greeter import Greeter

__all__ = ["Greeter", "HelloFeature"]


@sigcore.hookimpl
def sigcore_register_controllers(register: Callable[[str, type[Controller]], None]) -> None:
    """``controller="hello.greeter"`` in a world attaches :class:`Greeter`."""
    register("hello.greeter", Greeter)


@sigcore.hookimpl
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """``<plugin name="hello" .../>`` in a world enables :class:`HelloFeature`."""
    register(HelloFeature)
