"""Request and response types of the IK services (generated into ``sigcore_msgs`` with ``sigcore interfaces``)."""

from __future__ import annotations

from sigcore.api.types import QUAT, RESULT, VEC, _model

IkRequest = _model(
    "IkRequest",
    "Move an arm's hand to a point [m]. `arm`: left/right (gripper side) or an arm name. `position`: 'absolute' =\n"
    "world frame; 'relative' = robot base frame; anything else = offset, in base-frame axes, from the hand's\n"
    "position with the arm's joints at 0 (the URDF's default pose).",
    **VEC, arm=str, position=str,
)
IkResponse = _model("IkResponse", "Whether the arm got there (the reason in message if not).", done=bool, **RESULT)

IkSolveRequest = _model(
    "IkSolveRequest",
    "A target pose of arm `chain`'s tip link in `frame` ('world', or a link of the robot): position [m] and\n"
    "orientation (w, x, y, z; all 0 = position only). `position_only` ignores the orientation. `tolerance` [m]\n"
    "(0: 1e-4; rotation tolerance 10 rad/m times it). `move`: drive the arm there through its joint servos and\n"
    "answer when it has settled, or at `timeout` simulated seconds (0: the move's duration + 5 s); the move\n"
    "succeeds if the tip ends within 5 mm (or `tolerance` if larger) of the target.",
    **VEC, **QUAT, frame=str, chain=str, position_only=bool, tolerance=float, move=bool, timeout=float,
)
IkSolveResponse = _model(
    "IkSolveResponse",
    "The joint solution [rad] or [m] of the chain's joints, the solver's tip position error [m] and, after a\n"
    "move, the tip position error measured in the simulation [m] (-1 without a move). On failure: the closest\n"
    "configuration and its residual (unreachable), or the angles the arm reached and its measured error.",
    joint_names=list[str], joint_positions=list[float], solver_error=float, final_error=float, **RESULT,
)

__all__ = ["IkRequest", "IkResponse", "IkSolveRequest", "IkSolveResponse"]
