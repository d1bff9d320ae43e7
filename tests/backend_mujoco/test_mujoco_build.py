"""Building worlds: registration, layout, sizes, link frames, model files and errors."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
from mujoco_worlds import robot, run
from sigcore_backend_mujoco import MujocoBackend

from sigcore import plugins
from sigcore.backend import BackendError
from sigcore.world import Object, World

LINKS = ["base_link", "wheel_l", "wheel_r", "caster_f", "caster_b", "lidar_link", "arm_1", "arm_2", "hand"]

BOX_URDF = """<robot name="bin">
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


def test_registered_as_mujoco() -> None:
    """The plugin registers MujocoBackend under the name 'mujoco'."""
    assert plugins.get_backend("mujoco") is MujocoBackend
    assert MujocoBackend.name == "mujoco"


def test_parts_and_joints(make_world, build) -> None:
    """Robot parts are all URDF links, root first, fixed links included; objects and humans have 'main'."""
    b = build(make_world(robot() + '<object name="o" shape="sphere" size="0.1" pose="2 0 1"/>'
                         '<human name="h" pose="-3 0 0"/><agent name="mod"/>'))
    assert b.parts("bot") == LINKS
    assert b.joints("bot") == ["wheel_l_joint", "wheel_r_joint", "shoulder", "elbow"]
    assert b.parts("o") == ["main"] and b.joints("o") == []
    assert b.parts("h") == ["main"]
    with pytest.raises(BackendError, match="entities: bot, o, h"):
        b.parts("mod")


def test_primitive_sizes(make_world, build) -> None:
    """Box sizes are full lengths, cylinder and capsule lengths are full lengths, as the world format says."""
    b = build(make_world(
        '<object name="bx" shape="box" size="0.2 0.4 0.6" pose="0 0 1"/>'
        '<object name="sp" shape="sphere" size="0.1" pose="1 0 1"/>'
        '<object name="cy" shape="cylinder" size="0.05 0.3" pose="2 0 1"/>'
        '<object name="ca" shape="capsule" size="0.05 0.3" pose="3 0 1"/>'))
    size = {n: b.model.geom_size[b.model.geom(f"{n}/main").id] for n in ("bx", "sp", "cy", "ca")}
    np.testing.assert_allclose(size["bx"], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(size["sp"][0], 0.1)
    np.testing.assert_allclose(size["cy"][:2], [0.05, 0.15])
    np.testing.assert_allclose(size["ca"][:2], [0.05, 0.15])
    run(b, 1.0)
    assert b.get_pose("bx")[0][2] == pytest.approx(0.3, abs=2e-3)  # resting on its 0.6 m side


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
    np.testing.assert_allclose(pos, [1.0, 2.0 - 0.1, 0.72], atol=1e-9)
    np.testing.assert_allclose(quat, [math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)], atol=1e-9)
    np.testing.assert_allclose(b.get_pose("bot", "lidar_link")[0], [1.0, 2.1, 0.25], atol=1e-9)
    np.testing.assert_allclose(b.get_pose("bot", "main")[0], b.get_pose("bot")[0])
    np.testing.assert_allclose(b.get_joint_position("bot", "elbow"), [1.0, 1.9, 0.45], atol=1e-9)


def test_mesh_object(make_world, build, tmp_path: Path) -> None:
    """A mesh object is scaled and collides: a unit cube mesh at scale 0.2 rests with its centre 0.1 m up."""
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    b = build(make_world('<object name="m" mesh="cube.obj" scale="0.2" mass="0.5" pose="0 0 0.5"/>'))
    run(b, 1.0)
    assert b.get_pose("m")[0][2] == pytest.approx(0.1, abs=2e-3)
    assert b.get_mass("m") == pytest.approx(0.5)


def test_urdf_objects(make_world, build, tmp_path: Path) -> None:
    """A static URDF object stays welded; a dynamic one falls, with the world's mass when given."""
    (tmp_path / "bin.urdf").write_text(BOX_URDF)
    b = build(make_world('<object name="s" urdf="bin.urdf" static="true" pose="0 0 0.5"/>'
                         '<object name="d" urdf="bin.urdf" mass="4" pose="2 0 0.5"/>'
                         '<object name="u" urdf="bin.urdf" pose="4 0 0.5"/>'))
    run(b, 1.0)
    np.testing.assert_allclose(b.get_pose("s")[0], [0, 0, 0.5])
    assert b.get_pose("d")[0][2] == pytest.approx(0.0, abs=2e-3)
    assert b.get_mass("d") == pytest.approx(4.0)
    assert b.get_mass("u") == pytest.approx(2.0)
    with pytest.raises(BackendError, match="static"):
        b.set_dynamics_mode("s", True)


def test_urdf_link_friction(make_world, build, tmp_path: Path) -> None:
    """Link friction comes from <gazebo><mu1> or PyBullet's <contact><lateral_friction>; 0 is frictionless."""
    world = make_world(robot())
    urdf = (tmp_path / "bot.urdf").read_text()
    contact = '<contact><lateral_friction value="0.3"/></contact>'
    urdf = urdf.replace('<link name="hand">', '<link name="hand">' + contact)
    (tmp_path / "bot.urdf").write_text(urdf)
    b = build(world)
    geom = {link: int(np.flatnonzero(b.model.geom_bodyid == b.model.body(f"bot/{link}").id)[0])
            for link in ("caster_f", "hand", "arm_1")}
    assert b.model.geom_friction[geom["caster_f"], 0] == 0.0
    assert b.model.geom_condim[geom["caster_f"]] == 1
    assert b.model.geom_friction[geom["hand"], 0] == pytest.approx(0.3)
    assert b.model.geom_friction[geom["arm_1"], 0] == pytest.approx(1.0)


def test_fixed_robot_stays(make_world, build) -> None:
    """A fixed robot's root is welded: driving its wheels does not move it."""
    b = build(make_world(robot(pose="0 0 0.3 0 0 0", extra=' fixed="true"')))
    b.set_joint_velocity("bot", "wheel_l_joint", 5.0)
    run(b, 0.5)
    np.testing.assert_allclose(b.get_pose("bot")[0], [0, 0, 0.3])
    assert b.get_joint_velocity("bot", "wheel_l_joint") == pytest.approx(5.0, rel=1e-2)


def test_missing_collision_mesh_names_entity(make_world, build, tmp_path: Path) -> None:
    """A URDF collision mesh that does not exist is a BackendError naming the robot and the file."""
    world = make_world(robot())
    (tmp_path / "bot.urdf").write_text((tmp_path / "bot.urdf").read_text().replace(
        '<geometry><box size="0.4 0.3 0.1"/></geometry>',
        '<geometry><mesh filename="meshes/nope.stl"/></geometry>'))
    with pytest.raises(BackendError, match=r"robot 'bot'.*meshes/nope\.stl"):
        build(world)


def test_massless_moving_link_names_entity(make_world, build, tmp_path: Path) -> None:
    """A movable link without <inertial> is a BackendError naming the robot and saying what to add."""
    world = make_world(robot())
    urdf = (tmp_path / "bot.urdf").read_text()
    start = urdf.index('<link name="wheel_l">')
    end = urdf.index("</inertial>", start) + len("</inertial>")
    (tmp_path / "bot.urdf").write_text(urdf[:start] + '<link name="wheel_l">' + urdf[end:])
    with pytest.raises(BackendError, match=r"robot 'bot'.*<inertial>"):
        build(world)


def test_missing_object_mesh_names_entity(tmp_path: Path) -> None:
    """A mesh file that disappeared after parsing is a BackendError naming the object."""
    world = World(agents=(Object(name="cup", mesh=Path("cup.obj")),), source=tmp_path / "w.xml")
    with pytest.raises(BackendError, match="object 'cup'.*cup.obj"):
        MujocoBackend().build(world)


def test_deterministic(make_world, build) -> None:
    """Two builds of one world stepped with the same inputs give bitwise-identical qpos."""
    world = make_world(robot() + '<object name="o" shape="box" size="0.1 0.1 0.1" pose="0.6 0.3 0.05"/>'
                       '<object name="c" shape="cylinder" size="0.03 0.1" graspable="true" '
                       'pose="-0.1 0 0.8"/>')
    runs = []
    for _ in range(2):
        b = build(world)
        b.attach("bot", "hand", "c")
        b.set_joint_velocity("bot", "wheel_l_joint", 3.0)
        b.set_joint_velocity("bot", "wheel_r_joint", 4.0)
        b.set_joint_target("bot", "shoulder", 0.4)
        for i in range(600):
            if i % 50 == 0:
                b.apply_wrench("o", None, np.array([2.0, 0, 0]), np.zeros(3))
            b.step()
        runs.append(b.data.qpos.tobytes())
    assert runs[0] == runs[1]


def test_same_urdf_twice(make_world, build) -> None:
    """Two robots from one URDF get separate bodies, named after each robot."""
    second = robot(pose="3 0 0 0 0 0").replace('name="bot"', 'name="bot2"')
    b = build(make_world(robot() + second))
    offset = b.get_pose("bot2", "hand")[0] - b.get_pose("bot", "hand")[0]
    np.testing.assert_allclose(offset, [3, 0, 0], atol=1e-9)
    assert mujoco.mj_name2id(b.model, mujoco.mjtObj.mjOBJ_BODY, "bot2/hand") >= 0
