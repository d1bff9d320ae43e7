"""Errors of the IK feature. Each carries its data and says what would be valid.

They subclass :class:`sigcore.agent.exceptions.ApiError`, so a service handler that raises one answers with
``success = false`` and the message.
"""

from __future__ import annotations

from collections.abc import Iterable

from sigcore.agent.exceptions import ApiError, UnreachableError
from sigcore.text import quote


class IkError(ApiError):
    """Base of the IK feature's errors."""


class UnknownChainError(IkError):
    """No kinematic chain (arm) of that name on the robot.

    Attributes:
        robot: Robot name.
        chain: The requested name.
        valid: Names that would have been accepted.
    """

    def __init__(self, robot: str, chain: str, valid: Iterable[str]) -> None:
        self.robot, self.chain, self.valid = robot, chain, tuple(valid)
        super().__init__(f"robot '{robot}' has no arm {quote(chain)}; valid: {', '.join(self.valid) or 'none'}")


class UnknownFrameError(IkError):
    """A target frame that is neither ``world`` nor a link of the robot.

    Attributes:
        frame: The requested frame.
        valid: ``world`` and the robot's link names.
    """

    def __init__(self, frame: str, valid: Iterable[str]) -> None:
        self.frame, self.valid = frame, tuple(valid)
        super().__init__(f"unknown frame {quote(frame)}; valid: {', '.join(self.valid)}")


class InvalidTargetError(IkError):
    """A target with a non-finite number, a zero quaternion or a bad tolerance or timeout."""


class NoSolutionError(IkError, UnreachableError):
    """The solver found no configuration within the tolerance (the target is out of reach or out of the limits).

    The error response carries the closest configuration: ``joint_names``, ``joint_positions``, ``solver_error``
    (the residual) and ``final_error`` -1 (nothing moved).

    Attributes:
        position_error: Residual distance of the best configuration found [m].
        rotation_error: Residual rotation angle of the best configuration [rad] (0 for position-only targets).
        joint_positions: That best configuration, chain joints in order [rad] or [m].
    """

    def __init__(self, chain: str, position_error: float, rotation_error: float, tolerance: float,
                 joint_positions: Iterable[float], position_only: bool, joint_names: Iterable[str] = ()) -> None:
        self.position_error, self.rotation_error = position_error, rotation_error
        self.joint_positions = tuple(float(a) for a in joint_positions)
        rot = "" if position_only else f", rotation residual {rotation_error:.3g} rad"
        super().__init__(
            f"target unreachable for arm '{chain}' within the joint limits: residual {position_error:.4g} m"
            f"{rot} (tolerance {tolerance:g} m); closest joint positions "
            f"[{', '.join(f'{a:.4f}' for a in self.joint_positions)}]",
            {"joint_names": list(joint_names), "joint_positions": list(self.joint_positions),
             "solver_error": position_error, "final_error": -1.0},
        )


class MoveError(IkError):
    """The arm did not reach the target: it stopped (blocked, overloaded) or was still off at the timeout farther
    than the move tolerance, or a newer request or a reset superseded the move.

    The error response carries where the arm got to: ``joint_positions`` (the chain's measured angles), ``final_error``
    (the tip's measured distance from the target [m]) and ``solver_error``.
    """
