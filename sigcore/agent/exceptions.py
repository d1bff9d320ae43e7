"""Errors of the agent API. Each carries a message that says what was wrong and what would be valid."""

from __future__ import annotations

from enum import StrEnum

from ..errors import ApiError, SigcoreError

__all__ = ["ApiError", "ControllerError", "GraspError", "GraspRefusal", "UnreachableError"]


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


class UnreachableError(ApiError):
    """No arm pose puts the hand at the target (too far, too close, beyond a joint limit, or no solution within the
    tolerance); the message gives the target and why. The IK feature's error carries the closest configuration too
    (``sigcore_ik.exceptions.NoSolutionError``)."""
