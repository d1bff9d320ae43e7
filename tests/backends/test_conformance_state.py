"""Conformance: registration, layout, poses, velocities, wrenches, masses and centres of mass, on every backend."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conformance_worlds import robot, run

from sigcore import plugins
from sigcore.backend import Backend
from sigcore.errors import BackendError
from sigcore.geometry import quat_from_rpy
from sigcore.world import Object, World

MODELS = Path(__file__).resolve().parents[2] / "worlds" / "models"

LINKS = ["base_link", "wheel_l", "wheel_r", "caster_f", "caster_b", "lidar_link", "arm_1", "arm_2", "hand"]

URDF_EPS = 1e-6
"""Tolerance [m] of poses computed from URDF numbers: PyBullet parses them as 32-bit floats (1e-7 relative)."""

STICK_URDF = """<robot name="stick">
  <link name="stick_link">
    <inertial><origin xyz="0.3 0 0"/><mass value="2"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.05 0.05"/></geometry></collision>
  </link>
</robot>"""

BIN_URDF = """<robot name="bin">
  <link name="bin_link">
    <inertial><origin xyz="0.05 0 0.1"/><mass value="2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
</robot>"""

CUBE_OBJ = "\n".join(
    [f"v {x} {y} {z}" for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    + ["f 1 3 4 2", "f 5 6 8 7", "f 1 2 6 5", "f 3 7 8 4", "f 1 5 7 3", "f 2 4 8 6"]
) + "\n"


def test_registered_under_its_name(backend_name: str) -> None:
    """The registry maps the name to a Backend subclass whose ``name`` is that name."""
    cls = plugins.get_backend(backend_name)
    assert issubclass(cls, Backend)
    assert cls.name == backend_name


def test_parts_and_joints(make_world, build) -> None:
    """Robot parts are all URDF links, root first, fixed links included; objects have 'main'; a person its feet
    'main' then its body's links, and its joints."""
    b = build(make_world(robot() + '<object name="o" shape="sphere" size="0.1" pose="2 0 1"/>'
                         '<human name="h" pose="-3 0 0"/><agent name="mod"/>'))
    assert b.parts("bot") == LINKS
    assert b.joints("bot") == ["wheel_l_joint", "wheel_r_joint", "shoulder", "elbow"]
    assert b.parts("o") == ["main"] and b.joints("o") == []
    assert b.parts("h")[:3] == ["main", "body", "waist"] and len(b.parts("h")) == 28
    assert len(b.joints("h")) == 22 and "l_knee" in b.joints("h")
    with pytest.raises(BackendError, match="entities: bot, o, h"):
        b.parts("mod")
    with pytest.raises(BackendError, match="parts: base_link"):
        b.get_pose("bot", "nope")


def test_primitive_sizes(make_world, build) -> None:
    """Box sizes are full lengths, cylinder and capsule lengths full lengths: each, let go 1 cm above the
    ground, rests at its half height (within 3 mm: contact penetration and solver softness). (Dropped from 1 m,
    PyBullet's cylinder lands on its rim and topples; see docs/backends.md.)"""
    b = build(make_world(
        '<object name="bx" shape="box" size="0.2 0.4 0.6" pose="0 0 0.31"/>'
        '<object name="sp" shape="sphere" size="0.1" pose="1 0 0.11"/>'
        '<object name="cy" shape="cylinder" size="0.05 0.3" pose="2 0 0.16"/>'
        '<object name="ca" shape="capsule" size="0.05 0.3" pose="3 0 0.21"/>'))
    run(b, 1.0)
    assert b.get_pose("bx")[0][2] == pytest.approx(0.3, abs=3e-3)
    assert b.get_pose("sp")[0][2] == pytest.approx(0.1, abs=3e-3)
    assert b.get_pose("cy")[0][2] == pytest.approx(0.15, abs=3e-3)
    assert b.get_pose("ca")[0][2] == pytest.approx(0.15 + 0.05, abs=3e-3)


def test_urdf_object_scale(make_world, build, tmp_path: Path) -> None:
    """A URDF object's ``scale`` multiplies every length of it on every backend: a ball let go above the middle
    of the clean-up world's table (top at 0.70 m) scaled by 1.5 rests on the top at 1.05 m (within 3 mm)."""
    (tmp_path / "table.urdf").write_text((MODELS / "table" / "table.urdf").read_text())
    b = build(make_world('<object name="t" urdf="table.urdf" scale="1.5" static="true" pose="0 0 0"/>'
                         '<object name="ball" shape="sphere" size="0.05" pose="0 0 1.2"/>'))
    run(b, 1.0)
    assert b.get_pose("ball")[0][2] == pytest.approx(1.05 + 0.05, abs=3e-3)


def test_masses(make_world, build) -> None:
    """Object mass is the world's; robot mass is the sum of the URDF <inertial> masses only."""
    b = build(make_world(robot() + '<object name="o" shape="box" size="0.1 0.1 0.1" mass="0.7" pose="2 0 1"/>'
                         '<human name="h" mass="60" pose="-3 0 0"/>'))
    assert b.get_mass("o") == pytest.approx(0.7)
    assert b.get_mass("bot") == pytest.approx(10 + 0.5 + 0.5 + 0.1 + 0.1 + 0.5 + 0.3 + 0.05)
    assert b.get_mass("h") == pytest.approx(60)


def test_link_frames_are_urdf_frames(make_world, build) -> None:
    """A part's pose is its URDF link frame composed with the robot pose (yaw 90 deg, x=1 y=2)."""
    b = build(make_world(robot(pose=f"1 2 0 0 0 {math.pi / 2}")))
    pos, quat = b.get_pose("bot", "hand")
    np.testing.assert_allclose(pos, [1.0, 2.0 - 0.1, 0.72], atol=URDF_EPS)
    np.testing.assert_allclose(quat, [math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)], atol=URDF_EPS)
    np.testing.assert_allclose(b.get_pose("bot")[0], [1.0, 2.0, 0.0], atol=URDF_EPS)
    np.testing.assert_allclose(b.get_pose("bot", "lidar_link")[0], [1.0, 2.1, 0.25], atol=URDF_EPS)
    np.testing.assert_allclose(b.get_pose("bot", "main")[0], b.get_pose("bot")[0])
    np.testing.assert_allclose(b.get_joint_position("bot", "elbow"), [1.0, 1.9, 0.45], atol=URDF_EPS)


def test_pose_round_trip(make_world, build) -> None:
    """set_pose then get_pose returns the position (1e-9 m) and (w, x, y, z) quaternion (1e-7: PyBullet
    renormalises it on the way) that were set, for dynamic and static objects and a robot whose base frame is
    not its centre of mass."""
    b = build(make_world(robot() + '<object name="o" shape="box" size="0.1 0.2 0.3" pose="2 0 1"/>'
                         '<object name="s" shape="box" size="1 1 1" static="true" pose="5 0 0.5"/>'))
    q = quat_from_rpy(0.3, -0.2, 1.1)
    for entity in ("o", "s", "bot"):
        b.set_pose(entity, np.array([1.0, -2.0, 3.0]), q)
        pos, quat = b.get_pose(entity)
        np.testing.assert_allclose(pos, [1.0, -2.0, 3.0], atol=1e-9)
        np.testing.assert_allclose(quat, q, atol=1e-7)
    b.set_pose("o", position=np.array([0.0, 0.0, 2.0]))
    np.testing.assert_allclose(b.get_pose("o")[1], q, atol=1e-7)  # None keeps the orientation
    b.set_pose("bot", quaternion=np.array([1.0, 0.0, 0.0, 0.0]))
    np.testing.assert_allclose(b.get_pose("bot")[0], [1.0, -2.0, 3.0], atol=1e-9)  # None keeps the position


def test_pose_after_step(make_world, build) -> None:
    """After one step, get_pose describes the integrated state: x advanced by v dt."""
    b = build(make_world('<object name="o" shape="sphere" size="0.1" pose="0 0 5"/>'))
    b.set_velocity("o", linear=np.array([3.0, 0.0, 0.0]))
    b.step()
    assert b.get_pose("o")[0][0] == pytest.approx(3.0 * 0.002, rel=1e-7)  # PyBullet: 1e-8 off


def test_get_poses_is_get_pose_for_every_part(make_world, build) -> None:
    """get_poses (one call for many parts: what the viewer reads between steps) gives, row by row, exactly what
    get_pose gives for each (entity, part), after steps that moved them; an unknown part is refused like get_pose
    refuses it, naming the part."""
    from sigcore.errors import BackendRefusal

    b = build(make_world(robot() + '<object name="o" shape="box" size="0.1 0.2 0.3" pose="2 0 1 0.4 0.5 0.6"/>'
                         '<human name="h" pose="-3 0 0"/>'))
    b.set_velocity("o", np.array([1.0, 0.0, 0.5]), np.array([0.3, -0.7, 1.5]))
    for _ in range(20):
        b.step()
    parts = [("bot", None), *[("bot", link) for link in LINKS], ("o", None), ("o", "main"), ("h", None)]
    poses = b.get_poses(parts)
    assert poses.shape == (len(parts), 7)
    for row, (entity, part) in zip(poses, parts, strict=True):
        pos, quat = b.get_pose(entity, part)
        assert np.array_equal(row, np.concatenate([pos, quat]))
    assert b.get_poses([]).shape == (0, 7)
    with pytest.raises(BackendRefusal, match="elbow_link"):
        b.get_poses([("bot", None), ("bot", "elbow_link")])


def test_set_velocity_then_get(make_world, build) -> None:
    """set_velocity then get_velocity gives the same world-frame linear and angular velocity, rotated body
    too."""
    b = build(make_world('<object name="o" shape="box" size="0.1 0.2 0.3" pose="0 0 2 0.4 0.5 0.6"/>'))
    b.set_velocity("o", np.array([1.0, 2.0, -0.5]), np.array([0.3, -0.7, 1.5]))
    lin, ang = b.get_velocity("o")
    np.testing.assert_allclose(lin, [1.0, 2.0, -0.5], atol=1e-9)
    np.testing.assert_allclose(ang, [0.3, -0.7, 1.5], atol=1e-9)


def test_part_velocity_of_spinning_robot(make_world, build) -> None:
    """A part's linear velocity is that of its frame origin: omega x r for a robot spun about z in the air."""
    b = build(make_world(robot(pose="0 0 5 0 0 0")))
    b.set_gravity_mode("bot", False)
    b.set_velocity("bot", linear=np.zeros(3), angular=np.array([0.0, 0.0, 2.0]))
    lin, ang = b.get_velocity("bot", "lidar_link")  # lidar origin at (0.1, 0, 0.25) from the base frame
    np.testing.assert_allclose(ang, [0, 0, 2.0], atol=1e-9)
    np.testing.assert_allclose(lin, [0.0, 0.2, 0.0], atol=URDF_EPS)
    np.testing.assert_allclose(b.get_velocity("bot")[0], 0.0, atol=1e-9)  # the base frame origin is on the axis


def test_wrench_at_com_gives_f_over_m(make_world, build, tmp_path: Path) -> None:
    """A force at the CoM of a body whose CoM is off its frame accelerates it at F/m (1e-6) without spinning
    it; the wrench lasts one step."""
    (tmp_path / "stick.urdf").write_text(STICK_URDF)
    b = build(make_world('<object name="st" urdf="stick.urdf" pose="0 0 3"/>'))
    b.set_gravity_mode("st", False)
    force = np.array([1.0, -2.0, 4.0])
    for _ in range(100):
        b.apply_wrench("st", None, force, np.zeros(3))
        b.step()
    lin, ang = b.get_velocity("st")
    np.testing.assert_allclose(lin, force / 2.0 * 0.2, rtol=1e-6)
    np.testing.assert_allclose(ang, 0.0, atol=1e-9)
    np.testing.assert_allclose(b.get_com("st"), b.get_pose("st")[0] + [0.3, 0, 0], atol=URDF_EPS)
    b.step()
    np.testing.assert_allclose(b.get_velocity("st")[0], lin, rtol=1e-9)  # nothing applied any more


def test_torque_spins_sphere(make_world, build) -> None:
    """A world-frame torque T on a sphere (I = 2/5 m r^2) gives angular acceleration T/I about its axis (1e-4:
    engines compute a sphere's inertia from its shape)."""
    b = build(make_world('<object name="s" shape="sphere" size="0.1" mass="2" pose="0 0 3 0.3 0.2 0.1"/>'))
    b.set_gravity_mode("s", False)
    inertia = 0.4 * 2.0 * 0.1 ** 2
    for _ in range(50):
        b.apply_wrench("s", None, np.zeros(3), np.array([0.0, 0.0, 0.08]))
        b.step()
    np.testing.assert_allclose(b.get_velocity("s")[1], [0, 0, 0.08 / inertia * 0.1], rtol=1e-4, atol=1e-9)


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
    assert b.get_velocity("o")[0][0] == pytest.approx(2.0 / 4.0 * 0.2, rel=1e-6)
    before = b.get_mass("bot")
    b.set_mass("bot", 2 * before)
    assert b.get_mass("bot") == pytest.approx(2 * before)


def test_com_of_link(make_world, build) -> None:
    """get_com of a robot link is its URDF inertial origin in the world."""
    b = build(make_world(robot(pose="1 0 0 0 0 0")))
    np.testing.assert_allclose(b.get_com("bot", "arm_1"), [1.0 - 0.1, 0, 0.15 + 0.15], atol=URDF_EPS)
    np.testing.assert_allclose(b.get_com("bot"), [1.0, 0, 0.1], atol=URDF_EPS)


def test_mesh_object(make_world, build, tmp_path: Path) -> None:
    """A mesh object is scaled and collides: a unit cube mesh at scale 0.2 rests with its centre 0.1 m up
    (within 3 mm)."""
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    b = build(make_world('<object name="m" mesh="cube.obj" scale="0.2" mass="0.5" pose="0 0 0.5"/>'))
    run(b, 1.0)
    assert b.get_pose("m")[0][2] == pytest.approx(0.1, abs=3e-3)
    assert b.get_mass("m") == pytest.approx(0.5)


def test_urdf_objects(make_world, build, tmp_path: Path) -> None:
    """A static URDF object stays put; a dynamic one let go 5 cm up lands flat on its frame (within 3 mm), with
    the world's mass when given. (Dropped from 0.5 m, PyBullet's box with its centre of mass 5 cm off-centre
    tips over on landing; see docs/backends.md.)"""
    (tmp_path / "bin.urdf").write_text(BIN_URDF)
    b = build(make_world('<object name="s" urdf="bin.urdf" static="true" pose="0 0 0.5"/>'
                         '<object name="d" urdf="bin.urdf" mass="4" pose="2 0 0.05"/>'
                         '<object name="u" urdf="bin.urdf" pose="4 0 0.5"/>'))
    run(b, 1.0)
    np.testing.assert_allclose(b.get_pose("s")[0], [0, 0, 0.5], atol=URDF_EPS)
    assert b.get_pose("d")[0][2] == pytest.approx(0.0, abs=3e-3)
    assert b.get_mass("d") == pytest.approx(4.0)
    assert b.get_mass("u") == pytest.approx(2.0)
    with pytest.raises(BackendError, match="static"):
        b.set_dynamics_mode("s", True)


def test_fixed_robot_stays(make_world, build) -> None:
    """A fixed robot's root is welded: driving its wheels does not move it."""
    b = build(make_world(robot(pose="0 0 0.3 0 0 0", extra=' fixed="true"')))
    b.set_joint_velocity("bot", "wheel_l_joint", 5.0)
    run(b, 0.5)
    np.testing.assert_allclose(b.get_pose("bot")[0], [0, 0, 0.3], atol=URDF_EPS)
    assert b.get_joint_velocity("bot", "wheel_l_joint") == pytest.approx(5.0, rel=1e-2)


def test_missing_collision_mesh_names_entity(make_world, build, tmp_path: Path) -> None:
    """A URDF collision mesh that does not exist is a BackendError naming the robot and the file."""
    (tmp_path / "bot.urdf").write_text((tmp_path / "bot.urdf").read_text().replace(
        '<geometry><box size="0.4 0.3 0.1"/></geometry>',
        '<geometry><mesh filename="meshes/nope.stl"/></geometry>'))
    world = make_world(robot())  # the world reads its URDFs once, when parsed
    with pytest.raises(BackendError, match=r"robot 'bot'.*meshes/nope\.stl"):
        build(world)


def test_massless_moving_link_names_entity(make_world, build, tmp_path: Path) -> None:
    """A movable link without <inertial> is a BackendError naming the robot and saying what to add."""
    urdf = (tmp_path / "bot.urdf").read_text()
    start = urdf.index('<link name="wheel_l">')
    end = urdf.index("</inertial>", start) + len("</inertial>")
    (tmp_path / "bot.urdf").write_text(urdf[:start] + '<link name="wheel_l">' + urdf[end:])
    world = make_world(robot())  # the world reads its URDFs once, when parsed
    with pytest.raises(BackendError, match=r"robot 'bot'.*<inertial>"):
        build(world)


def test_missing_object_mesh_names_entity(backend_name: str, tmp_path: Path) -> None:
    """A mesh file that disappeared after parsing is a BackendError naming the object."""
    world = World(agents=(Object(name="cup", mesh=Path("cup.obj")),), source=tmp_path / "w.xml")
    with pytest.raises(BackendError, match="object 'cup'.*cup.obj"):
        plugins.get_backend(backend_name)().build(world)


def test_same_urdf_twice(make_world, build) -> None:
    """Two robots from one URDF are separate entities with their own parts."""
    second = robot(pose="3 0 0 0 0 0").replace('name="bot"', 'name="bot2"')
    b = build(make_world(robot() + second))
    offset = b.get_pose("bot2", "hand")[0] - b.get_pose("bot", "hand")[0]
    np.testing.assert_allclose(offset, [3, 0, 0], atol=URDF_EPS)
