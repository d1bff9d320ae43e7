"""Conformance: grasping through the robot handle (grasp radius rule), carrying, releasing, on every backend."""

from __future__ import annotations

import numpy as np
import pytest
from conformance_worlds import robot, run

from sigcore.agent import GraspError, GraspRefusal
from sigcore.errors import BackendError
from sigcore.geometry import quat_conj, quat_mul, quat_to_matrix

CAN = '<object name="can" shape="cylinder" size="0.03 0.1" mass="0.2" graspable="true" pose="-0.1 0 0.79"/>'
FIXED = ' fixed="true"'


def _relative(b, part: str, obj: str) -> tuple[np.ndarray, np.ndarray]:
    hp, hq = b.get_pose("bot", part)
    op, oq = b.get_pose(obj)
    return quat_to_matrix(hq).T @ (op - hp), quat_mul(quat_conj(hq), oq)


def test_grasp_within_radius_carries(make_world, simulate) -> None:
    """RobotObj.grasp within the radius (0.07 m < 0.2 m) attaches: moving the arm carries the object, its pose
    relative to the hand kept within 2 mm / 0.01 rad."""
    sim = simulate(make_world(robot(extra=FIXED) + CAN))
    b = sim.backend
    rel_pos, rel_quat = _relative(b, "hand", "can")
    sim.robot("bot").grasp("hand", "can")
    b.set_joint_target("bot", "shoulder", 0.6)
    b.set_joint_target("bot", "elbow", 0.5)
    sim.step(1000)
    pos, quat = _relative(b, "hand", "can")
    np.testing.assert_allclose(pos, rel_pos, atol=0.002)
    assert abs(float(np.dot(quat, rel_quat))) > 1 - 1e-4
    assert b.get_pose("can")[0][2] > 0.4  # carried, not fallen
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.6, abs=0.02)


def test_grasp_beyond_radius_refused(make_world, simulate) -> None:
    """RobotObj.grasp of an object beyond the grasp radius (0.5 m > 0.2 m) is refused as TOO_FAR; nothing is
    attached (the object falls)."""
    can = CAN.replace('pose="-0.1 0 0.79"', 'pose="0.6 0 0.5"')
    sim = simulate(make_world(robot(extra=FIXED) + can))
    with pytest.raises(GraspError) as err:
        sim.robot("bot").grasp("hand", "can")
    assert err.value.reason is GraspRefusal.TOO_FAR
    sim.step(250)
    assert sim.backend.get_pose("can")[0][2] < 0.2


def test_attach_does_not_jump(make_world, build) -> None:
    """Attaching an object at some distance and angle from the hand does not move it (within 0.5 mm)."""
    can = CAN.replace('pose="-0.1 0 0.79"', 'pose="-0.05 0.03 0.85 0.3 0 0.5"')
    b = build(make_world(robot(extra=FIXED) + can))
    b.set_gravity_mode("can", False)
    before = b.get_pose("can")[0]
    b.attach("bot", "hand", "can")
    run(b, 0.5)
    np.testing.assert_allclose(b.get_pose("can")[0], before, atol=5e-4)


def test_release_drops(make_world, simulate) -> None:
    """After RobotObj.release the object falls under gravity (more than 10 cm in 0.5 s), while the hand stays
    (5 mm)."""
    sim = simulate(make_world(robot(extra=FIXED) + CAN))
    bot = sim.robot("bot")
    bot.grasp("hand", "can")
    sim.backend.set_joint_target("bot", "shoulder", 1.2)
    sim.step(750)
    z0 = sim.backend.get_pose("can")[0][2]
    hand = sim.backend.get_pose("bot", "hand")[0]
    assert bot.release("hand") == "can"
    sim.step(250)
    assert sim.backend.get_pose("can")[0][2] < z0 - 0.1
    np.testing.assert_allclose(sim.backend.get_pose("bot", "hand")[0], hand, atol=0.005)


def test_held_object_does_not_collide_with_its_robot(make_world, build) -> None:
    """A grasped object overlapping the robot's arm touches none of the robot's parts; released, it does."""
    b = build(make_world(robot(extra=FIXED) + CAN.replace('pose="-0.1 0 0.79"', 'pose="-0.1 0 0.72"')))
    b.attach("bot", "hand", "can")
    run(b, 0.2)
    names = {(b.part_of(x)[0], b.part_of(y)[0]) for x, y in b.contacts()}
    assert ("bot", "can") not in names and ("can", "bot") not in names
    b.detach("bot", "hand", "can")
    b.step()
    names = {(b.part_of(x)[0], b.part_of(y)[0]) for x, y in b.contacts()}
    assert ("bot", "can") in names or ("can", "bot") in names


def test_attach_refused_for_non_gripper_pairs(make_world, build) -> None:
    """Attaching a non-graspable object, or to a part that is not a gripper, is a BackendError listing the
    possible pairs."""
    box = '<object name="box" shape="box" size="0.1 0.1 0.1" pose="1 0 0.05"/>'
    b = build(make_world(robot() + CAN + box))
    with pytest.raises(BackendError, match="hand \\+ can"):
        b.attach("bot", "hand", "box")
    with pytest.raises(BackendError, match="hand \\+ can"):
        b.attach("bot", "arm_2", "can")
