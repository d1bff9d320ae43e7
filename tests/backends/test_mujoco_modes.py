"""MuJoCo only: with gravity off, a servo holds its angle with no steady error."""

from __future__ import annotations

import pytest
from conformance_worlds import robot, run


def test_gravity_off_robot_arm_does_not_sag(make_world, build_mujoco) -> None:
    """With gravity off a fixed robot's arm holds an angle with no steady error (no gravity load on the
    servo)."""
    b = build_mujoco(make_world(robot(pose="0 0 0 0 0 0", extra=' fixed="true"')))
    b.set_gravity_mode("bot", False)
    b.set_joint_target("bot", "shoulder", 1.0)
    run(b, 2.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(1.0, abs=1e-6)
