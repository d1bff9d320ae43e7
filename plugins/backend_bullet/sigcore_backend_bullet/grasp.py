"""Grasps as ``JOINT_FIXED`` constraints created at the current relative pose, removed on release.

``createConstraint`` frames are relative to each link's *inertial* frame (centre of mass); the parent frame is
the object's inertial pose in the hand's inertial frame, the child frame the identity, so the constraint holds
the pose of the moment. While attached, the object does not collide with any link of the robot holding it: the
backend holds the pair apart with pair filters (:mod:`.pairs`), which keep the broadphase and other contacts as
they are.
"""

from __future__ import annotations

import pybullet as pb

from .layout import BASE, EntityIndex

MAX_FORCE = 1e4
"""Force limit [N] of a grasp constraint (PyBullet's default, 500 N, lets a heavy object sag)."""


def inertial_pose(client: int, body: int, link: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """World pose of a link's inertial frame (``(x, y, z, w)`` quaternion)."""
    if link == BASE:
        pos, orn = pb.getBasePositionAndOrientation(body, physicsClientId=client)
        return tuple(pos), tuple(orn)
    state = pb.getLinkState(body, link, computeForwardKinematics=1, physicsClientId=client)
    return tuple(state[0]), tuple(state[1])


def attach(client: int, robot: EntityIndex, link: int, obj: EntityIndex) -> int:
    """Weld ``obj``'s base to ``robot``'s ``link`` where they are now; returns the constraint id."""
    hand_pos, hand_orn = inertial_pose(client, robot.body, link)
    obj_pos, obj_orn = inertial_pose(client, obj.body, BASE)
    inv_pos, inv_orn = pb.invertTransform(hand_pos, hand_orn)
    rel_pos, rel_orn = pb.multiplyTransforms(inv_pos, inv_orn, obj_pos, obj_orn)
    cid = pb.createConstraint(robot.body, link, obj.body, BASE, pb.JOINT_FIXED, [0, 0, 0], rel_pos, [0, 0, 0],
                              rel_orn, [0, 0, 0, 1], physicsClientId=client)
    pb.changeConstraint(cid, maxForce=MAX_FORCE, physicsClientId=client)
    return int(cid)


def detach(client: int, cid: int) -> None:
    """Remove the constraint ``cid``."""
    pb.removeConstraint(cid, physicsClientId=client)
