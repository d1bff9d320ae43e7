"""Gravity, dynamics and collision modes, held humans, and reset."""

from __future__ import annotations

import pytest
from mujoco_worlds import robot, run

BOX = '<object name="o" shape="box" size="0.2 0.2 0.2" mass="1" pose="0 0 1"/>'


def test_gravity_off_robot_arm_does_not_sag(make_world, build) -> None:
    """With gravity off a fixed robot's arm holds an angle with no steady error (no gravity load on the
    servo)."""
    b = build(make_world(robot(pose="0 0 0 0 0 0", extra=' fixed="true"')))
    b.set_gravity_mode("bot", False)
    b.set_joint_target("bot", "shoulder", 1.0)
    run(b, 2.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(1.0, abs=1e-6)
