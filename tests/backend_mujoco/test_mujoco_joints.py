"""Joint servos: position targets, velocities, instant angles, torques and the differential drive."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mujoco_worlds import robot, run

from sigcore.backend import BackendError

FIXED = ' fixed="true"'


def _yaw(q: np.ndarray) -> float:
    w, x, y, z = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def test_arms_hold_initial_angle(make_world, build) -> None:
    """Arm joints start as position servos holding their initial angle (within 0.01 rad under gravity)."""
    b = build(make_world(robot()))
    run(b, 1.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.0, abs=0.01)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(0.0, abs=0.01)


def test_joint_target_reached(make_world, build) -> None:
    """set_joint_target drives the joint to the angle: within 0.01 rad after 2 s (gravity load / kp <
    0.005)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_joint_target("bot", "shoulder", 0.8)
    b.set_joint_target("bot", "elbow", -0.6)
    run(b, 2.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.8, abs=0.01)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(-0.6, abs=0.01)
    assert abs(b.get_joint_velocity("bot", "shoulder")) < 1e-3


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


def test_joint_velocity_stops_at_limit(make_world, build) -> None:
    """A joint driven at a velocity stops at its URDF limit (the servo's target is clamped to the range)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_gravity_mode("bot", False)
    b.set_joint_velocity("bot", "elbow", 2.0)
    run(b, 2.0)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(2.5, abs=0.01)


def test_set_joint_angle_instant(make_world, build) -> None:
    """set_joint_angle is instant (the hand moves at once) and the servo then holds the angle, sagging by the
    gravity torque over kp (2.3 N m / 200 = 0.011 rad for the horizontal arm)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_joint_angle("bot", "shoulder", math.pi / 2)
    assert b.get_joint_angle("bot", "shoulder") == math.pi / 2
    np.testing.assert_allclose(b.get_pose("bot", "hand")[0], [-0.1 + 0.57, 0, 0.15], atol=1e-9)
    run(b, 1.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(math.pi / 2 + 2.27 / 200, abs=0.002)


def test_joint_torque_for_one_step(make_world, build) -> None:
    """add_joint_torque acts during the next step only: Δqdot = τ dt / I on a lifted, unbraked wheel."""
    b = build(make_world(robot(pose="0 0 0.5 0 0 0", extra=FIXED)))
    b.set_joint_velocity("bot", "wheel_l_joint", 0.0, max_torque=1e-9)
    b.add_joint_torque("bot", "wheel_l_joint", 1.0)
    b.step()
    after_one = b.get_joint_velocity("bot", "wheel_l_joint")
    assert after_one == pytest.approx(1.0 * 0.002 / 0.0025, rel=1e-4)
    b.step()
    assert b.get_joint_velocity("bot", "wheel_l_joint") == pytest.approx(after_one, rel=1e-4)
    assert not b.data.qfrc_applied.any()


def test_wheel_motor_exact_without_overshoot(make_world, build) -> None:
    """A lifted wheel reaches its commanded velocity in 2 steps and holds it (within 0.1 %), overshooting <
    0.2 %."""
    b = build(make_world(robot(pose="0 0 0.5 0 0 0", extra=FIXED)))
    b.set_joint_velocity("bot", "wheel_r_joint", 8.0, max_torque=20.0)
    speeds = []
    for _ in range(100):
        b.step()
        speeds.append(b.get_joint_velocity("bot", "wheel_r_joint"))
    assert max(speeds) <= 8.0 * 1.002
    assert min(speeds[2:]) >= 8.0 * 0.999


def test_wheel_motor_torque_limit(make_world, build) -> None:
    """A wheel motor limited to τ accelerates a lifted wheel (I = 0.0025 kg m^2) at τ / I, within 1 %."""
    b = build(make_world(robot(pose="0 0 0.5 0 0 0", extra=FIXED)))
    b.set_joint_velocity("bot", "wheel_r_joint", 8.0, max_torque=0.005)
    run(b, 0.5)
    assert b.get_joint_velocity("bot", "wheel_r_joint") == pytest.approx(0.005 / 0.0025 * 0.5, rel=0.01)


def test_wheel_target_refused(make_world, build) -> None:
    """A position target on a drive wheel is refused, naming the joints that take one."""
    b = build(make_world(robot()))
    with pytest.raises(BackendError, match="shoulder, elbow"):
        b.set_joint_target("bot", "wheel_l_joint", 1.0)


def test_drive_straight(make_world, build) -> None:
    """Both wheels at ω for T = 2 s (after 0.5 s spin-up) move the robot ω·r·T forward, within 1 %."""
    b = build(make_world(robot()))
    omega, radius, seconds = 5.0, 0.1, 2.0
    for joint in ("wheel_l_joint", "wheel_r_joint"):
        b.set_joint_velocity("bot", joint, omega, 20.0)
    run(b, 0.5)
    start = b.get_pose("bot")[0]
    run(b, seconds)
    pos, quat = b.get_pose("bot")
    assert pos[0] - start[0] == pytest.approx(omega * radius * seconds, rel=0.01)
    assert abs(pos[1] - start[1]) < 0.005
    assert abs(_yaw(quat)) < 0.002


def test_turn_in_place(make_world, build) -> None:
    """Wheels at -ω and +ω turn the robot in place at 2ωr/separation, heading within 2 %, position within 1
    cm."""
    b = build(make_world(robot()))
    omega, radius, separation, seconds = 2.0, 0.1, 0.4, 1.0
    b.set_joint_velocity("bot", "wheel_l_joint", -omega, 20.0)
    b.set_joint_velocity("bot", "wheel_r_joint", omega, 20.0)
    run(b, 0.5)
    yaw0 = _yaw(b.get_pose("bot")[1])
    run(b, seconds)
    pos, quat = b.get_pose("bot")
    assert _yaw(quat) - yaw0 == pytest.approx(2 * omega * radius / separation * seconds, rel=0.02)
    assert np.linalg.norm(pos[:2]) < 0.01
