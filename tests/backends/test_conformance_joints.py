"""Conformance: joint servos, instant angles, joint torques and the differential drive, on every backend."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conformance_worlds import robot, run, stop_shoulder, turn_shoulder

from sigcore.errors import BackendError
from sigcore.geometry import quat_yaw

FIXED = ' fixed="true"'


def test_arms_hold_initial_angle(make_world, build) -> None:
    """Arm joints start as position servos holding their initial angle (within 0.01 rad under gravity)."""
    b = build(make_world(robot()))
    run(b, 1.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.0, abs=0.01)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(0.0, abs=0.01)


def test_joint_target_reached(make_world, build) -> None:
    """set_joint_target drives the joint to the angle: within 0.015 rad after 2 s (the servo sags by the gravity
    torque over kp, < 0.012 rad here) and stops (|qdot| < 0.02 rad/s: PyBullet's servo has a ripple of
    ±0.01 rad/s at rest, MuJoCo's none)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_joint_target("bot", "shoulder", 0.8)
    b.set_joint_target("bot", "elbow", -0.6)
    run(b, 2.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.8, abs=0.015)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(-0.6, abs=0.015)
    assert abs(b.get_joint_velocity("bot", "shoulder")) < 0.02


def test_joint_velocity_tracked(make_world, build) -> None:
    """set_joint_velocity turns an arm joint at that velocity under gravity (mean within 2 %), and velocity 0
    then holds it (drift < 1e-3 rad in 0.5 s)."""
    b = build(make_world(robot(extra=FIXED)))
    speeds = turn_shoulder(b)
    assert np.mean(speeds) == pytest.approx(0.5, rel=0.02)
    held = stop_shoulder(b)
    run(b, 0.5)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(held, abs=1e-3)


def test_joint_velocity_stops_at_limit(make_world, build) -> None:
    """A joint driven at a velocity stops at its URDF limit (within 0.01 rad)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_gravity_mode("bot", False)
    b.set_joint_velocity("bot", "elbow", 2.0)
    run(b, 2.0)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(2.5, abs=0.01)


def test_set_joint_angle_instant(make_world, build) -> None:
    """set_joint_angle is instant (the hand moves at once, 1e-6) and the servo then holds the angle, sagging by the
    gravity torque over kp (2.27 N m / 200 = 0.011 rad for the horizontal arm, within 2 mrad)."""
    b = build(make_world(robot(extra=FIXED)))
    b.set_joint_angle("bot", "shoulder", math.pi / 2)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(math.pi / 2, abs=1e-12)
    np.testing.assert_allclose(b.get_pose("bot", "hand")[0], [-0.1 + 0.57, 0, 0.15], atol=1e-6)
    run(b, 1.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(math.pi / 2 + 2.27 / 200, abs=0.002)


def test_joint_torque_for_one_step(make_world, build) -> None:
    """add_joint_torque acts during the next step only: Δqdot = τ dt / I on a lifted, unbraked wheel (0.1 %)."""
    b = build(make_world(robot(pose="0 0 0.5 0 0 0", extra=FIXED)))
    b.set_joint_velocity("bot", "wheel_l_joint", 0.0, max_torque=1e-9)
    b.add_joint_torque("bot", "wheel_l_joint", 1.0)
    b.step()
    after_one = b.get_joint_velocity("bot", "wheel_l_joint")
    assert after_one == pytest.approx(1.0 * 0.002 / 0.0025, rel=1e-3)
    b.step()
    assert b.get_joint_velocity("bot", "wheel_l_joint") == pytest.approx(after_one, rel=1e-3)


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
    """Both wheels at ω for T = 2 s (after 0.5 s spin-up) move the robot ω·r·T forward within 1 %, sideways
    < 5 mm, heading < 0.002 rad (wheels do not slip: friction 1, frictionless casters)."""
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
    assert abs(quat_yaw(quat)) < 0.002


def test_turn_in_place(make_world, build) -> None:
    """Wheels at -ω and +ω turn the robot in place at 2ωr/separation: heading within 2 % (contact patch of a
    cylinder wheel scrubbing), position within 1.5 cm (MuJoCo drifts < 1 mm, PyBullet 10 mm)."""
    b = build(make_world(robot()))
    omega, radius, separation, seconds = 2.0, 0.1, 0.4, 1.0
    b.set_joint_velocity("bot", "wheel_l_joint", -omega, 20.0)
    b.set_joint_velocity("bot", "wheel_r_joint", omega, 20.0)
    run(b, 0.5)
    yaw0 = quat_yaw(b.get_pose("bot")[1])
    run(b, seconds)
    pos, quat = b.get_pose("bot")
    assert quat_yaw(quat) - yaw0 == pytest.approx(2 * omega * radius / separation * seconds, rel=0.02)
    assert np.linalg.norm(pos[:2]) < 0.015


def test_drive_arc(make_world, build) -> None:
    """Wheels at ω_l = 3, ω_r = 5 rad/s for 2 s follow the kinematic arc (v = r(ω_l+ω_r)/2, w =
    r(ω_r-ω_l)/s): end position within 2 cm, heading within 0.02 rad."""
    b = build(make_world(robot()))
    wl, wr, radius, separation, seconds = 3.0, 5.0, 0.1, 0.4, 2.0
    b.set_joint_velocity("bot", "wheel_l_joint", wl, 20.0)
    b.set_joint_velocity("bot", "wheel_r_joint", wr, 20.0)
    run(b, 0.5)
    pos0, q0 = b.get_pose("bot")
    yaw0 = quat_yaw(q0)
    run(b, seconds)
    pos, quat = b.get_pose("bot")
    v, w = radius * (wl + wr) / 2, radius * (wr - wl) / separation
    yaw1 = yaw0 + w * seconds
    expected = pos0[:2] + v / w * np.array([math.sin(yaw1) - math.sin(yaw0), math.cos(yaw0) - math.cos(yaw1)])
    np.testing.assert_allclose(pos[:2], expected, atol=0.02)
    assert quat_yaw(quat) == pytest.approx(yaw1, abs=0.02)
