"""MuJoCo only: a velocity servo without ripple (PyBullet's has ±0.01 rad/s, test_conformance_joints.py)."""

from __future__ import annotations

import numpy as np
import pytest
from conformance_worlds import robot, run, stop_shoulder, turn_shoulder

FIXED = ' fixed="true"'


def test_joint_velocity_tracked_under_gravity(make_world, build_mujoco) -> None:
    """set_joint_velocity turns an arm joint at that velocity under gravity: within 2 % (the servo's lag
    behind its moving target changes with the gravity torque: d(tau_g / kp)/dt ~ 0.005 rad/s here)."""
    b = build_mujoco(make_world(robot(extra=FIXED)))
    speeds = turn_shoulder(b)
    assert np.mean(speeds) == pytest.approx(0.5, rel=0.02)
    assert np.std(speeds) < 0.01
    held = stop_shoulder(b)
    run(b, 0.5)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(held, abs=1e-3)  # velocity 0 holds the arm
