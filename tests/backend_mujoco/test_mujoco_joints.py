"""Joint servos: position targets, velocities, instant angles, torques and the differential drive."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mujoco_worlds import robot, run

FIXED = ' fixed="true"'


def _yaw(q: np.ndarray) -> float:
    w, x, y, z = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def test_joint_velocity_tracked_under_gravity(make_world, build) -> None:
    """set_joint_velocity turns an arm joint at that velocity under gravity: within 2 % (the servo's lag
    behind its moving target changes with the gravity torque: d(tau_g / kp)/dt ~ 0.005 rad/s here)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_joint_velocity("bot", "shoulder", 0.5)
    run(b, 0.5)
    speeds = []
    for _ in range(250):
        b.step()
        speeds.append(b.get_joint_velocity("bot", "shoulder"))
    assert np.mean(speeds) == pytest.approx(0.5, rel=0.02)
    assert np.std(speeds) < 0.01
    b.set_joint_velocity("bot", "shoulder", 0.0)
    run(b, 0.5)
    held = b.get_joint_angle("bot", "shoulder")
    run(b, 0.5)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(held, abs=1e-3)  # velocity 0 holds the arm
