"""The arms of sigbot (worlds/models/sigbot): closed-form inverse kinematics with the hand pointing down."""

from __future__ import annotations

import math

from sigcore.agent.exceptions import UnreachableError

SHOULDER_Y = 0.20
"""Shoulders at (0, ±0.20, 1.15) in the base frame [m]."""
SHOULDER_Z = 1.15
UPPER_ARM = 0.37
"""Shoulder pitch axis to elbow [m]."""
FOREARM = 0.31
"""Elbow to wrist pitch axis [m]."""
HAND = 0.15
"""Wrist pitch axis to the grasp point between the fingertips [m]."""
JOINTS = ("shoulder_pan_joint", "shoulder_pitch_joint", "elbow_joint", "wrist_pitch_joint", "wrist_roll_joint")
"""Arm joints without the ``l_`` / ``r_`` prefix, in the order of the poses."""
LIMITS = ((-1.57, 1.57), (-0.8, 3.0), (-0.1, 2.5), (-2.2, 2.2), (-3.14, 3.14))
TUCK = (0.0, 0.4, 2.4, -2.1, 0.0)
"""Carry pose: hand at (0.35, ±0.20, 0.99) in the base frame, above table height."""

Pose = tuple[float, float, float, float, float]


def joint_names(side: str) -> list[str]:
    """Joint names of the ``"l"`` or ``"r"`` arm, in pose order."""
    return [f"{side}_{j}" for j in JOINTS]


def hand_down(side: str, x: float, y: float, z: float) -> Pose:
    """Arm pose putting the grasp point of the ``"l"`` / ``"r"`` hand at (x, y, z) [m] in the base frame, the
    hand pointing down (elbow up).

    Raises:
        UnreachableError: too far, too close, or beyond a joint limit.
    """
    sy = SHOULDER_Y if side == "l" else -SHOULDER_Y
    pan = math.atan2(y - sy, x)
    reach = math.hypot(x, y - sy)
    drop = z + HAND - SHOULDER_Z
    d2 = reach * reach + drop * drop
    c = (d2 - UPPER_ARM**2 - FOREARM**2) / (2 * UPPER_ARM * FOREARM)
    if not -1.0 <= c <= 1.0:
        raise UnreachableError(f"({x:.3f}, {y:.3f}, {z:.3f}) is {math.sqrt(d2):.3f} m from the {side} wrist's "
                               f"shoulder; reachable: {abs(UPPER_ARM - FOREARM):.2f}..{UPPER_ARM + FOREARM:.2f}")
    elbow = math.acos(c)
    pitch = math.atan2(reach, -drop) - math.atan2(FOREARM * math.sin(elbow), UPPER_ARM + FOREARM * math.cos(elbow))
    pose = (pan, pitch, elbow, -(pitch + elbow), 0.0)
    for name, angle, (lo, hi) in zip(JOINTS, pose, LIMITS, strict=True):
        if not lo <= angle <= hi:
            raise UnreachableError(f"({x:.3f}, {y:.3f}, {z:.3f}) needs {side}_{name} = {angle:.3f}, beyond "
                                   f"[{lo}, {hi}]")
    return pose
