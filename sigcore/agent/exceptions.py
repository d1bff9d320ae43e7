"""Errors of the agent API. Each carries a message that says what was wrong and what would be valid."""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum
from typing import Any

from ..errors import SigcoreError


class ApiError(SigcoreError, ValueError):
    """A request to the agent API was refused (unknown name, NaN, out of range, wrong mode...).

    The simulation is unaffected; transports turn this into an error response.

    Args:
        message: What was wrong and what would be valid.
        fields: Response fields the error response carries besides ``success`` and ``message`` (e.g. the residual
            of a failed IK solve); those the response type does not have are dropped. Empty by default.
    """

    def __init__(self, message: str = "", fields: Mapping[str, Any] | None = None) -> None:
        super().__init__(message)
        self.fields: dict[str, Any] = dict(fields or {})


class GraspRefusal(StrEnum):
    """Why SIGVerse (and sigcore) refuse a grasp."""

    UNKNOWN_PART = "unknown_part"
    NOT_A_GRIPPER = "not_a_gripper"
    UNKNOWN_OBJECT = "unknown_object"
    ALREADY_GRASPING = "already_grasping"
    HELD_BY_ANOTHER = "held_by_another"
    NOT_GRASPABLE = "not_graspable"
    TOO_FAR = "too_far"


class GraspError(ApiError):
    """A grasp was refused; ``reason`` is one of :class:`GraspRefusal`."""

    def __init__(self, reason: GraspRefusal, message: str) -> None:
        self.reason = reason
        super().__init__(f"grasp refused ({reason.value}): {message}")


class ControllerError(SigcoreError, RuntimeError):
    """A user controller could not be found or created; the message names the agent and what is valid."""
