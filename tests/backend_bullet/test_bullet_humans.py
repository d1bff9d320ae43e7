"""Persons on the PyBullet backend: their generated URDF as a held (kinematic) body or a rigid mannequin (see
``sigcore_backend_bullet.base``), their parts, joints, postures, pushes, refusals and colours."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from sigcore_backend_bullet import BulletBackend

from sigcore.errors import BackendRefusal
from sigcore.geometry import quat_from_rpy, quat_mul, quat_rotate
from sigcore.world import World, parse_world
from sigcore.world.appearance import link_colors

Make = Callable[[str], World]

ARM = {"waist": 0.2, "l_y_shoulder": 0.3, "l_p_shoulder": 0.8, "l_r_shoulder": -0.4, "l_elbow": 1.1}
"""A posture of the left arm (and the waist) [rad]."""

PUSHER_URDF = """<robot name="pusher">
  <link name="base_link">
    <inertial><origin xyz="0 0 0.15"/><mass value="15"/>
      <inertia ixx="0.2" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.2"/></inertial>
    <collision><origin xyz="0 0 0.15"/><geometry><box size="0.3 0.3 0.3"/></geometry></collision>
  </link>
</robot>
"""


@pytest.fixture
def make(tmp_path: Path) -> Make:
    """``make(body_xml)``: a world file with that body (and the pusher URDF next to it), parsed."""
    (tmp_path / "pusher.urdf").write_text(PUSHER_URDF)

    def world(body: str) -> World:
        path = tmp_path / "w.xml"
        path.write_text(f'<world name="w" timestep="0.002">\n{body}\n</world>\n')
        return parse_world(path)

    return world


def build(world: World) -> BulletBackend:
    b = BulletBackend()
    b.build(world)
    return b


def run(b: BulletBackend, steps: int) -> None:
    for _ in range(steps):
        b.step()


def forward_kinematics(world: World, human: str, link: str, angles: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Pose (position, (w, x, y, z)) of ``link`` of ``human`` from the URDF's joints, its root at its world-file
    pose (``UrdfModel.link_pose``: no engine involved)."""
    entity = next(e for e in world.entities if e.name == human)
    return world.urdf(human).model.link_pose(link, angles, entity.pose.xyz, quat_from_rpy(*entity.pose.rpy))


def same_rotation(a: np.ndarray, b: np.ndarray) -> float:
    """How far apart two unit quaternions are (0 for the same rotation, q and -q alike)."""
    return float(1.0 - abs(np.dot(a, b)))


def all_poses(b: BulletBackend, name: str) -> np.ndarray:
    return b.get_poses([(name, part) for part in b.parts(name)])


def test_parts_and_joints_are_the_urdf_links_and_movable_joints(make: Make) -> None:
    """A person's parts are its URDF links, the root 'main' (at the feet: the world-file pose) first; its joints
    the 22 movable ones in URDF order; unknown parts and joints are refused, listing the valid ones."""
    world = make('<human name="h" pose="1 2 0 0 0 0.5"/>')
    b = build(world)
    model = world.urdf("h").model
    assert b.parts("h") == [model.root] + [link for link in model.links if link != model.root]
    assert b.parts("h")[0] == "main" and "l_wrist" in b.parts("h")
    assert b.joints("h") == [j.name for j in model.movable_joints] and len(b.joints("h")) == 22
    pos, quat = b.get_pose("h")
    np.testing.assert_allclose(pos, [1, 2, 0], atol=1e-9)
    assert same_rotation(quat, quat_from_rpy(0, 0, 0.5)) < 1e-12
    np.testing.assert_array_equal(b.get_pose("h", "main")[0], pos)
    with pytest.raises(BackendRefusal, match="parts: main, body, waist"):
        b.get_pose("h", "nose")
    with pytest.raises(BackendRefusal, match="joints: waist, r_head"):
        b.get_joint_angle("h", "l_wrist")


@pytest.mark.parametrize("static", ["true", "false"])
def test_set_joint_angle_puts_the_wrist_where_the_urdf_puts_it(make: Make, static: str) -> None:
    """After set_joint_angle the l_wrist link is at the URDF's forward kinematics of those angles (1e-6 m, for a
    held person after 100 steps, for a mannequin at once), and get_joint_angle returns the angles."""
    world = make(f'<human name="h" pose="1 -1 0.3 0 0 2.0" static="{static}"/>')
    b = build(world)
    for joint, angle in ARM.items():
        b.set_joint_angle("h", joint, angle)
    if static == "true":
        run(b, 100)
    pos, quat = b.get_pose("h", "l_wrist")
    want_pos, want_quat = forward_kinematics(world, "h", "l_wrist", ARM)
    np.testing.assert_allclose(pos, want_pos, atol=1e-6)
    assert same_rotation(quat, want_quat) < 1e-10
    np.testing.assert_allclose(b.get_joint_position("h", "l_elbow"),
                               forward_kinematics(world, "h", "l_elbow", ARM)[0], atol=1e-6)
    assert {j: b.get_joint_angle("h", j) for j in ARM} == ARM
    assert np.linalg.norm(want_pos - forward_kinematics(world, "h", "l_wrist", {})[0]) > 0.3  # it did move


def test_held_human_is_not_moved_by_a_box_or_a_robot_pushing_it(make: Make) -> None:
    """A static person pushed by a 20 kg box (200 N, into its left thigh) and a 15 kg robot driven into its right
    shin at 0.5 m/s does not move at all (every link frame, every angle), and stops both: they touch its links."""
    world = make('<human name="h" pose="0 0 0"/>'
                 '<object name="box" shape="box" size="0.2 0.2 0.2" mass="20" pose="0.5 0.136 0.6"/>'
                 '<robot name="bot" urdf="pusher.urdf" pose="0.6 -0.136 0.02"/>')
    b = build(world)
    b.set_gravity_mode("box", False)
    before = all_poses(b, "h")
    touched: set[tuple[str, str]] = set()
    for _ in range(1000):
        b.apply_wrench("box", None, np.array([-200.0, 0.0, 0.0]), np.zeros(3))
        b.set_velocity("bot", np.array([-0.5, 0.0, 0.0]))
        b.step()
        for pair in b.contacts():
            touched |= {b.part_of(p) for p in pair}
    assert np.abs(all_poses(b, "h") - before).max() == 0.0
    assert all(b.get_joint_angle("h", j) == 0.0 for j in b.joints("h"))
    assert b.get_pose("box")[0][0] > 0.075 + 0.1 - 0.01  # in front of the thigh (radius 0.075), 1 cm at most in
    assert b.get_pose("bot")[0][0] > 0.06 + 0.15 - 0.01  # in front of the shin (radius 0.06)
    assert ("h", "l_hip") in touched and ("h", "r_knee") in touched


def test_human_moved_in_small_steps_pushes_a_light_box_away(make: Make) -> None:
    """A static person moved forward 1 mm per step with set_pose pushes a 0.5 kg box in its way ahead of it, and
    is exactly where it was put."""
    b = build(make('<human name="h" pose="0 0 0"/>'
                   '<object name="box" shape="box" size="0.2 0.2 0.2" mass="0.5" pose="0.5 0 0.1"/>'))
    for i in range(600):
        b.set_pose("h", np.array([0.001 * i, 0.0, 0.0]))
        b.step()
    x = b.get_pose("h")[0][0]
    assert x == pytest.approx(0.599, abs=1e-12)
    box = b.get_pose("box")[0]
    assert box[0] > 0.75  # pushed on from 0.5 m
    assert box[0] - 0.1 > x + 0.06  # in front of the shins


def test_human_arm_moved_by_set_joint_angle_pushes_a_box_off_a_pedestal(make: Make) -> None:
    """A static person raising its arm sideways into a 0.5 kg box on a pedestal pushes the box away."""
    b = build(make('<human name="h" pose="0 0 0"/>'
                   '<object name="ped" shape="box" size="0.2 0.2 1.0" static="true" pose="0 0.55 0.5"/>'
                   '<object name="box" shape="box" size="0.1 0.1 0.1" mass="0.5" pose="0 0.55 1.05"/>'))
    run(b, 50)
    start = b.get_pose("box")[0]
    for i in range(400):
        b.set_joint_angle("h", "l_p_shoulder", min(0.005 * i, 1.5))
        b.step()
    assert b.get_pose("h", "l_wrist")[0][1] > 0.7  # the arm is raised sideways
    assert np.linalg.norm(b.get_pose("box")[0] - start) > 0.1


def test_human_joints_have_no_motor(make: Make) -> None:
    """Targets, velocities and torques on a person's joint are refused (it has no motor: set_joint_angle poses it);
    an unknown joint is refused as for a robot, listing the joints."""
    b = build(make('<human name="h" pose="0 0 0"/>'))
    for call in (lambda: b.set_joint_target("h", "l_knee", -0.5), lambda: b.set_joint_velocity("h", "l_knee", 1.0),
                 lambda: b.add_joint_torque("h", "l_knee", 5.0)):
        with pytest.raises(BackendRefusal, match="joint 'l_knee' of human 'h' has no motor: .*set_joint_angle"):
            call()
    with pytest.raises(BackendRefusal, match="no movable joint 'knee'; joints: waist"):
        b.set_joint_target("h", "knee", 0.1)
    assert b.get_joint_angle("h", "l_knee") == 0.0


def test_motors_are_off(make: Make) -> None:
    """No PyBullet default motor is left on a person's joints (held or mannequin)."""
    b = build(make('<human name="h" pose="0 0 0"/><human name="m" pose="2 0 0" static="false"/>'))
    for name in ("h", "m"):
        e = b._entities[name]
        for j in e.joints.values():
            assert pb.getJointState(e.body, j.index, physicsClientId=b.client)[3] == 0.0  # applied motor torque
            assert pb.getJointInfo(e.body, j.index, physicsClientId=b.client)[2] in (pb.JOINT_REVOLUTE,
                                                                                       pb.JOINT_FIXED)
    run(b, 10)
    e = b._entities["h"]
    assert all(s[3] == 0.0 for s in pb.getJointStates(e.body, e.joint_indices, physicsClientId=b.client))


def test_mannequin_stands_on_its_feet_and_falls_rigid(make: Make) -> None:
    """A dynamic person dropped from 1 cm stands on its two feet (contacts with its ankle links) with its arm held
    out; pushed over at the chest it falls, its posture unchanged: the wrist keeps its pose in the torso frame."""
    b = build(make('<human name="h" pose="1 2 0.01" static="false"/>'))
    b.set_joint_angle("h", "l_p_shoulder", 0.6)
    run(b, 250)
    np.testing.assert_allclose(b.get_pose("h")[0], [1, 2, 0], atol=3e-3)
    assert {b.part_of(p) for pair in b.contacts() for p in pair} >= {("h", "l_ankle"), ("h", "r_ankle")}

    def wrist_in_torso() -> tuple[np.ndarray, np.ndarray]:
        (tp, tq), (wp, wq) = b.get_pose("h", "torso"), b.get_pose("h", "l_wrist")
        inv = np.array([tq[0], -tq[1], -tq[2], -tq[3]])
        return quat_rotate(inv, wp - tp), quat_mul(inv, wq)

    rel_pos, rel_quat = wrist_in_torso()
    for _ in range(100):
        b.apply_wrench("h", "torso", np.array([300.0, 0.0, 0.0]), np.zeros(3))
        b.step()
    run(b, 1000)
    assert b.get_com("h")[2] < 0.3  # lying on the ground
    new_pos, new_quat = wrist_in_torso()
    np.testing.assert_allclose(new_pos, rel_pos, atol=1e-6)
    assert same_rotation(new_quat, rel_quat) < 1e-10
    assert b.get_joint_angle("h", "l_p_shoulder") == 0.6
    assert np.linalg.norm(b.get_velocity("h")[0]) < 0.01  # at rest, not jittering


def test_no_self_collision(make: Make) -> None:
    """A mannequin whose arm passes through its torso stands still (its links do not collide with each other)."""
    b = build(make('<human name="h" pose="0 0 0.01" static="false"/>'))
    b.set_joint_angle("h", "l_p_shoulder", -0.4)  # the left hand inside the torso
    run(b, 500)
    np.testing.assert_allclose(b.get_pose("h")[0], [0, 0, 0], atol=3e-3)
    assert np.linalg.norm(b.get_velocity("h")[0]) < 0.01


def test_dynamics_mode_frees_and_holds_again(make: Make) -> None:
    """set_dynamics_mode(True) frees a static person (a push at its hips moves it), set_dynamics_mode(False) holds
    it again where it is (the same push then does nothing), its posture kept throughout."""
    b = build(make('<human name="h" pose="0 0 0"/>'))
    b.set_joint_angle("h", "r_elbow", 1.0)
    b.set_dynamics_mode("h", True)
    for _ in range(100):
        b.apply_wrench("h", "body", np.array([400.0, 0.0, 0.0]), np.zeros(3))
        b.step()
    assert b.get_com("h")[0] > 0.05
    b.set_dynamics_mode("h", False)
    held = all_poses(b, "h")
    for _ in range(200):
        b.apply_wrench("h", "body", np.array([400.0, 0.0, 0.0]), np.zeros(3))
        b.step()
    assert np.abs(all_poses(b, "h") - held).max() < 1e-12
    assert b.get_joint_angle("h", "r_elbow") == 1.0
    assert pb.getJointState(b._entities["h"].body, b._entities["h"].joints["r_elbow"].index,
                            physicsClientId=b.client)[0] == 1.0


def test_masses_are_the_urdf_inertials(make: Make) -> None:
    """get_mass is the world's mass, the sum of the URDF <inertial> masses, which a mannequin's links have."""
    world = make('<human name="h" mass="60" pose="0 0 0"/><human name="m" mass="80" pose="2 0 0" static="false"/>')
    b = build(world)
    assert b.get_mass("h") == pytest.approx(60.0) and b.get_mass("m") == pytest.approx(80.0)
    e = b._entities["m"]
    urdf = {link.get("name"): float(link.find("inertial/mass").get("value"))
            for link in world.urdf("m").root.findall("link")}
    names = {BASE_NAME: -1} | {pb.getJointInfo(e.body, i, physicsClientId=b.client)[12].decode(): i
                               for i in range(pb.getNumJoints(e.body, physicsClientId=b.client))}
    for name, link in names.items():
        assert pb.getDynamicsInfo(e.body, link, physicsClientId=b.client)[0] == pytest.approx(urdf[name])
    assert sum(urdf.values()) == pytest.approx(80.0)


BASE_NAME = "main"


def test_reset_after_a_mannequin_rebuild_and_with_added_humans(make: Make) -> None:
    """A mannequin posed (a new body) and a static person added while running: reset brings back the build
    state (the mannequin standing at its pose, joints at 0) and the added person as added, held again."""
    world = make('<human name="m" pose="0 0 0.01" static="false"/>')
    b = build(world)
    run(b, 100)
    b.set_joint_angle("m", "r_knee", -1.0)
    b.set_pose("m", np.array([0.0, 0.0, 1.0]))
    more = make('<human name="m" pose="0 0 0.01" static="false"/><human name="h" pose="3 0 0"/>')
    b.add_entities(more, ["h"])
    b.set_joint_angle("h", "l_knee", -0.7)
    b.set_dynamics_mode("h", True)
    run(b, 300)
    b.reset()
    np.testing.assert_allclose(b.get_pose("m")[0], [0, 0, 0.01], atol=1e-9)
    assert b.get_joint_angle("m", "r_knee") == 0.0 and b.get_joint_angle("h", "l_knee") == 0.0
    assert b._entities["m"].rigid and not b._entities["h"].rigid and b._posed == {"h"}
    before = all_poses(b, "h")
    for _ in range(100):
        b.apply_wrench("h", None, np.array([1000.0, 0.0, 0.0]), np.zeros(3))
        b.step()
    assert np.abs(all_poses(b, "h") - before).max() == 0.0
    np.testing.assert_allclose(b.get_pose("h")[0], [3, 0, 0], atol=1e-12)
    b.remove_entities(world, ["h"])
    assert b.parts("m")[0] == "main"
    with pytest.raises(BackendRefusal, match="no entity 'h'"):
        b.parts("h")


def test_camera_paints_human_links_their_colours(make: Make) -> None:
    """The renderer gives each link of a person its scene colour (link_colors), and the new body of a mannequin
    whose posture changed too."""
    world = make('<human name="h" pose="0 0 0"/><human name="m" pose="2 0 0" static="false"/>')
    b = build(world)
    renderer = b.renderer()

    def painted(name: str) -> dict[str, tuple[float, ...]]:
        e = b._entities[name]
        names = {-1: "main"} | {i: pb.getJointInfo(e.body, i, physicsClientId=b.client)[12].decode()
                                for i in range(pb.getNumJoints(e.body, physicsClientId=b.client))}
        return {names[row[1]]: tuple(row[7]) for row in pb.getVisualShapeData(e.body, physicsClientId=b.client)}

    renderer.snapshot()
    colors = link_colors(world, world.agent("h"))
    assert {"torso", "head", "l_ankle"} <= colors.keys()
    for name in ("h", "m"):
        got = painted(name)
        for link, color in colors.items():
            assert got[link] == pytest.approx(color)
    b.set_joint_angle("m", "l_elbow", 1.0)
    renderer.snapshot()
    got = painted("m")
    assert all(got[link] == pytest.approx(color) for link, color in colors.items())
