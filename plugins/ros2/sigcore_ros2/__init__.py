"""sigcore's ROS 2 transport: registers :class:`Ros2Transport` as ``"ros2"`` and the ``ros2`` feature that holds
its settings (``<plugin name="ros2" .../>`` in a world file).

rclpy is imported only when the transport starts, so ``sigcore plugins`` works without ROS 2.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from sigcore.feature import Feature
from sigcore.plugins import hookimpl
from sigcore.transport import Transport

from .config import Ros2Config, Ros2Feature
from .transport import Ros2Transport

__all__ = ["Ros2Config", "Ros2Feature", "Ros2Transport", "sigcore_register_commands", "sigcore_register_features",
           "sigcore_register_transports"]


@hookimpl
def sigcore_register_transports(register: Callable[[type[Transport]], None]) -> None:
    """Register the ROS 2 transport under the name ``"ros2"``."""
    register(Ros2Transport)


@hookimpl
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """Register the ``ros2`` feature (it only stores the transport's settings from the world file)."""
    register(Ros2Feature)


@hookimpl
def sigcore_register_commands(cli: Any) -> None:
    """``sigcore ros ...`` (topics, echo, hz, call, record: ROS 2 introspection for pip-only users) and
    ``sigcore bag play`` (a recording published on ROS 2); rclpy is imported only when one of them runs."""
    from .cli.commands import register

    register(cli)
