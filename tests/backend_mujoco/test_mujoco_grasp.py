"""Grasping: a weld switched on at the current relative pose, switched off on release."""

from __future__ import annotations

import numpy as np
import pytest
from mujoco_worlds import robot, run

from sigcore.errors import BackendError
from sigcore.geometry import quat_conj, quat_mul, quat_to_matrix

CAN = '<object name="can" shape="cylinder" size="0.03 0.1" mass="0.2" graspable="true" pose="-0.1 0 0.79"/>'
FIXED = ' fixed="true"'


def _relative(b, part: str, obj: str) -> tuple[np.ndarray, np.ndarray]:
    hp, hq = b.get_pose("bot", part)
    op, oq = b.get_pose(obj)
    return quat_to_matrix(hq).T @ (op - hp), quat_mul(quat_conj(hq), oq)


def test_attached_object_follows_hand(make_world, build) -> None:
    """After attach, moving the arm carries the object: its pose relative to the hand stays within 2 mm /
    0.01."""
    b = build(make_world(robot(extra=FIXED) + CAN))
    rel_pos, rel_quat = _relative(b, "hand", "can")
    b.attach("bot", "hand", "can")
    b.set_joint_target("bot", "shoulder", 0.6)
    b.set_joint_target("bot", "elbow", 0.5)
    run(b, 2.0)
    pos, quat = _relative(b, "hand", "can")
    np.testing.assert_allclose(pos, rel_pos, atol=0.002)
    assert abs(float(np.dot(quat, rel_quat))) > 1 - 1e-4
    assert b.get_pose("can")[0][2] > 0.4  # carried, not fallen
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.6, abs=0.02)


def test_detach_drops(make_world, build) -> None:
    """After detach the object falls under gravity (more than 10 cm in 0.5 s), while the hand stays."""
    b = build(make_world(robot(extra=FIXED) + CAN))
    b.attach("bot", "hand", "can")
    b.set_joint_target("bot", "shoulder", 1.2)
    run(b, 1.5)
    z0 = b.get_pose("can")[0][2]
    hand = b.get_pose("bot", "hand")[0]
    b.detach("bot", "hand", "can")
    run(b, 0.5)
    assert b.get_pose("can")[0][2] < z0 - 0.1
    np.testing.assert_allclose(b.get_pose("bot", "hand")[0], hand, atol=0.005)


def test_attach_refused_without_weld(make_world, build) -> None:
    """Attaching a non-graspable object, or to a part that is not a gripper, is a BackendError listing the
    pairs."""
    box = '<object name="box" shape="box" size="0.1 0.1 0.1" pose="1 0 0.05"/>'
    b = build(make_world(robot() + CAN + box))
    with pytest.raises(BackendError, match="hand \\+ can"):
        b.attach("bot", "hand", "box")
    with pytest.raises(BackendError, match="hand \\+ can"):
        b.attach("bot", "arm_2", "can")
