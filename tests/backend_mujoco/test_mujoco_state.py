"""Poses, velocities, free fall, wrenches, masses and centres of mass."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from mujoco_worlds import G, robot

from sigcore.geometry import quat_from_rpy

STICK_URDF = """<robot name="stick">
  <link name="stick_link">
    <inertial><origin xyz="0.3 0 0"/><mass value="2"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.05 0.05"/></geometry></collision>
  </link>
</robot>"""


def test_pose_round_trip(make_world, build) -> None:
    """set_pose then get_pose returns the position and (w, x, y, z) quaternion that were set."""
    b = build(make_world(robot() + '<object name="o" shape="box" size="0.1 0.2 0.3" pose="2 0 1"/>'
                         '<object name="s" shape="box" size="1 1 1" static="true" pose="5 0 0.5"/>'))
    q = quat_from_rpy(0.3, -0.2, 1.1)
    for entity in ("o", "s", "bot"):
        b.set_pose(entity, np.array([1.0, -2.0, 3.0]), q)
        pos, quat = b.get_pose(entity)
        np.testing.assert_allclose(pos, [1.0, -2.0, 3.0], atol=1e-12)
        np.testing.assert_allclose(quat, q, atol=1e-12)
    b.set_pose("o", position=np.array([0.0, 0.0, 2.0]))
    np.testing.assert_allclose(b.get_pose("o")[1], q, atol=1e-12)  # None keeps the orientation


def test_pose_after_step_matches_qpos(make_world, build) -> None:
    """After a step, get_pose describes the integrated state (not the state before the step)."""
    b = build(make_world('<object name="o" shape="sphere" size="0.1" pose="0 0 5"/>'))
    b.set_velocity("o", linear=np.array([3.0, 0.0, 0.0]))
    b.step()
    np.testing.assert_allclose(b.get_pose("o")[0], b.data.qpos[0:3], atol=1e-15)
    assert b.get_pose("o")[0][0] == pytest.approx(3.0 * 0.002)


def test_set_velocity_then_get(make_world, build) -> None:
    """set_velocity then get_velocity gives the same world-frame linear and angular velocity, rotated body
    too."""
    b = build(make_world('<object name="o" shape="box" size="0.1 0.2 0.3" pose="0 0 2 0.4 0.5 0.6"/>'))
    b.set_velocity("o", np.array([1.0, 2.0, -0.5]), np.array([0.3, -0.7, 1.5]))
    lin, ang = b.get_velocity("o")
    np.testing.assert_allclose(lin, [1.0, 2.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(ang, [0.3, -0.7, 1.5], atol=1e-12)


def test_part_velocity_of_spinning_robot(make_world, build) -> None:
    """A part's linear velocity is that of its frame origin: omega x r for a robot spun about z in the air."""
    b = build(make_world(robot(pose="0 0 5 0 0 0")))
    b.set_gravity_mode("bot", False)
    b.set_velocity("bot", angular=np.array([0.0, 0.0, 2.0]))
    lin, ang = b.get_velocity("bot", "lidar_link")  # lidar origin at (0.1, 0, 0.25) from the base frame
    np.testing.assert_allclose(ang, [0, 0, 2.0], atol=1e-12)
    np.testing.assert_allclose(lin, [0.0, 0.2, 0.0], atol=1e-12)


def test_drop_time(make_world, build) -> None:
    """A box dropped from 1 m (bottom face) touches the ground at t = sqrt(2h/g) within 2 steps (4 ms)."""
    b = build(make_world('<object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 1.05"/>'))
    expected = math.sqrt(2 * 1.0 / G)
    steps = 0
    while not b.contacts():
        b.step()
        steps += 1
        assert steps < 1000
    assert steps * 0.002 == pytest.approx(expected, abs=0.004)


def test_wrench_at_com_gives_f_over_m(make_world, build, tmp_path: Path) -> None:
    """A force at the CoM of a body whose CoM is off its frame accelerates it at F/m without spinning it."""
    (tmp_path / "stick.urdf").write_text(STICK_URDF)
    b = build(make_world('<object name="st" urdf="stick.urdf" pose="0 0 3"/>'))
    b.set_gravity_mode("st", False)
    force = np.array([1.0, -2.0, 4.0])
    for _ in range(100):
        b.apply_wrench("st", None, force, np.zeros(3))
        b.step()
    lin, ang = b.get_velocity("st")
    np.testing.assert_allclose(lin, force / 2.0 * 0.2, rtol=1e-9)
    np.testing.assert_allclose(ang, 0.0, atol=1e-12)
    np.testing.assert_allclose(b.get_com("st"), b.get_pose("st")[0] + [0.3, 0, 0], atol=1e-12)
    assert not b.data.xfrc_applied.any()  # cleared after the step


def test_torque_spins_sphere(make_world, build) -> None:
    """A torque T on a sphere (I = 2/5 m r^2) gives angular acceleration T/I about the torque's axis."""
    b = build(make_world('<object name="s" shape="sphere" size="0.1" mass="2" pose="0 0 3"/>'))
    b.set_gravity_mode("s", False)
    inertia = 0.4 * 2.0 * 0.1 ** 2
    for _ in range(50):
        b.apply_wrench("s", None, np.zeros(3), np.array([0.0, 0.0, 0.08]))
        b.step()
    np.testing.assert_allclose(b.get_velocity("s")[1], [0, 0, 0.08 / inertia * 0.1], rtol=1e-6)


def test_set_mass(make_world, build) -> None:
    """set_mass sets get_mass, and the same force then gives the acceleration F/m of the new mass."""
    b = build(make_world('<object name="o" shape="box" size="0.2 0.2 0.2" mass="1" pose="0 0 3"/>'
                         + robot(pose="3 0 0 0 0 0")))
    b.set_mass("o", 4.0)
    assert b.get_mass("o") == pytest.approx(4.0)
    b.set_gravity_mode("o", False)
    for _ in range(100):
        b.apply_wrench("o", None, np.array([2.0, 0.0, 0.0]), np.zeros(3))
        b.step()
    assert b.get_velocity("o")[0][0] == pytest.approx(2.0 / 4.0 * 0.2, rel=1e-9)
    before = b.get_mass("bot")
    b.set_mass("bot", 2 * before)
    assert b.get_mass("bot") == pytest.approx(2 * before)


def test_com_of_link(make_world, build) -> None:
    """get_com of a robot link is its URDF inertial origin in the world."""
    b = build(make_world(robot(pose="1 0 0 0 0 0")))
    np.testing.assert_allclose(b.get_com("bot", "arm_1"), [1.0 - 0.1, 0, 0.15 + 0.15], atol=1e-9)
