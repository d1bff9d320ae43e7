"""sigcore's referee: the ``Referee/text/points`` viewer service and the clean-up task's rules (feature
``referee``), and a scripted clean-up robot (controller ``cleanup.robot``)."""

from __future__ import annotations

from collections.abc import Callable

from sigcore.agent.controller import Controller
from sigcore.feature import Feature
from sigcore.plugins import hookimpl

from .demo import CleanupRobot
from .events import RefereeEvent, parse_message
from .referee import Referee

__all__ = ["CleanupRobot", "Referee", "RefereeEvent", "parse_message", "sigcore_register_controllers",
           "sigcore_register_features"]


@hookimpl
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """Register the referee as feature ``"referee"``."""
    register(Referee)


@hookimpl
def sigcore_register_controllers(register: Callable[[str, type[Controller]], None]) -> None:
    """Register the scripted clean-up robot as controller ``"cleanup.robot"``."""
    register("cleanup.robot", CleanupRobot)
