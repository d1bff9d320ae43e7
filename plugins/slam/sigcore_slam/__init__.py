"""SLAM for sigcore: registers the ``slam`` feature (``<plugin name="slam" agent="robot_000"/>``)."""

from __future__ import annotations

from collections.abc import Callable

from sigcore.feature import Feature
from sigcore.plugins import hookimpl

from .config import SlamConfig
from .feature import SlamFeature, SlamState
from .grid import OccupancyGrid
from .mapfile import load_map, save_map
from .se2 import Pose2

__all__ = ["OccupancyGrid", "Pose2", "SlamConfig", "SlamFeature", "SlamState", "load_map", "save_map",
           "sigcore_register_features"]


@hookimpl
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """Register :class:`SlamFeature` under the name ``"slam"``."""
    register(SlamFeature)
