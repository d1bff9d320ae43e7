"""The TF tree of the core (``Frames``): one root, every link in it, poses composed from it equal the backend's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sigcore.geometry import quat_mul, quat_rotate
from sigcore.sim import Simulation
from sigcore.sim.frames import WORLD
from sigcore.world import UrdfError, WorldError, parse_world, read_urdf

ROOT = Path(__file__).parent.parent
SIM_WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"
WORLDS = {"cleanup": ROOT / "worlds" / "cleanup.xml", "arm6": ROOT / "worlds" / "arm6.xml"}
BACKENDS = ("mujoco", "bullet")


def _robot(sim: Simulation) -> str:
    return next(a.name for a in sim.world.agents if a.kind == "robot")


def _parents(sim: Simulation, robot: str) -> dict[str, tuple[str, np.ndarray, np.ndarray]]:
    """child -> (parent, xyz, wxyz) of the whole tree at the current state, the robot's root at the backend's pose
    (ground truth in place of the wheel odometry); fails if a frame gets two parents."""
    static = sim.frames.static()
    tree = {child: (parent, np.array(xyz), np.array(wxyz)) for child, (parent, xyz, wxyz) in static.items()}
    dynamic = sim.frames.transforms(robot) + sim.frames.entity_transforms()
    dynamic += [t for person in sim.frames.people for t in sim.frames.transforms(person)]
    if sim.frames.root_mode(robot) == "odom":
        pos, quat = sim.backend.get_pose(robot)
        dynamic.append((WORLD, sim.entities.urdf(robot).root, tuple(pos), tuple(quat)))
        del tree["odom"]  # world -> odom -> base_link replaced by world -> base_link
    for parent, child, xyz, wxyz in dynamic:
        assert child not in tree, f"frame '{child}' has two parents"
        tree[child] = (parent, np.array(xyz), np.array(wxyz))
    return tree


def _in_world(tree: dict[str, tuple[str, np.ndarray, np.ndarray]], frame: str) -> tuple[np.ndarray, np.ndarray]:
    pos, quat, seen = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), set()
    while frame != WORLD:
        assert frame in tree and frame not in seen, f"frame '{frame}' has no chain to '{WORLD}'"
        seen.add(frame)
        parent, xyz, wxyz = tree[frame]
        pos, quat = xyz + quat_rotate(wxyz, pos), quat_mul(wxyz, quat)
        frame = parent
    return pos, quat


def _move_joints(sim: Simulation, robot: str) -> None:
    """Every movable joint to a non-zero position inside its limits."""
    rng = np.random.default_rng(7)
    for joint in sim.entities.urdf(robot).movable_joints:
        low, high = (joint.lower, joint.upper) if joint.lower is not None and joint.upper is not None else (-2, 2)
        value = float(rng.uniform(0.3, 0.9)) * (high if abs(high) >= abs(low) else low)
        assert value != 0.0
        sim.backend.set_joint_angle(robot, joint.name, value)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("world", sorted(WORLDS))
def test_composed_link_poses_equal_the_backend_poses(world: str, backend: str) -> None:
    """Every URDF link has exactly one chain to 'world', and its pose composed from the static transforms and the
    joint transforms (root at the backend's pose) equals the backend's within 1e-6 m and 1e-6, joints moved."""
    sim = Simulation(parse_world(WORLDS[world]), backend)
    robot = _robot(sim)
    _move_joints(sim, robot)
    tree = _parents(sim, robot)
    assert {parent for parent, _, _ in tree.values()} - set(tree) == {WORLD}  # one root
    for link in sim.entities.urdf(robot).links:
        pos, quat = _in_world(tree, link)
        bpos, bquat = sim.backend.get_pose(robot, link)  # every link has a body on both backends (none merged)
        assert np.abs(pos - bpos).max() < 1e-6, link
        assert min(np.abs(quat - bquat).max(), np.abs(quat + bquat).max()) < 1e-6, link
    for entity in sim.frames.entities:
        assert np.abs(_in_world(tree, entity)[0] - sim.backend.get_pose(entity)[0]).max() < 1e-12
    for person in sim.frames.people:  # a person's REP-155 link frames, joints moved, equal its backend links
        _move_joints(sim, person)
        tree = _parents(sim, robot)
        for link in sim.entities.urdf(person).links:
            pos, quat = _in_world(tree, sim.frames.name(person, link))
            bpos, bquat = sim.backend.get_pose(person, link)
            assert np.abs(pos - bpos).max() < 1e-6, link
            assert min(np.abs(quat - bquat).max(), np.abs(quat + bquat).max()) < 1e-6, link


def test_the_roots_of_robots_with_a_drive_fixed_and_free() -> None:
    """A robot with a <drive> hangs under odom, a fixed one is static under world, a free one moves under world."""
    cleanup = Simulation(parse_world(WORLDS["cleanup"]), "mujoco")
    assert cleanup.frames.root_mode("robot_000") == "odom" and cleanup.frames.static()["odom"][0] == WORLD
    assert all(parent != WORLD for parent, _ in cleanup.frames.moving("robot_000"))
    arm = Simulation(parse_world(WORLDS["arm6"]), "mujoco")
    assert arm.frames.root_mode("arm_0") == "fixed" and arm.frames.static()["base_link"][0] == WORLD
    assert "odom" not in arm.frames.static()
    text = SIM_WORLD.read_text()
    start = text.index("<drive")
    free = Simulation(parse_world(SIM_WORLD, text[:start] + text[text.index("/>", start) + 2:]), "mujoco")
    assert free.frames.root_mode("bot") == "free" and free.frames.moving("bot")[0] == (WORLD, "base_link")
    parent, child, xyz, _ = free.frames.transforms("bot")[0]
    assert (parent, child) == (WORLD, "base_link")
    assert np.allclose(xyz, free.backend.get_pose("bot")[0], atol=1e-12)
    assert "odom" not in free.frames.static()


def test_transforms_take_the_published_joint_positions() -> None:
    """Given the joint positions of joint_states, the transforms use them instead of reading the backend."""
    sim = Simulation(parse_world(WORLDS["cleanup"]), "mujoco")
    joints = sim.entities.urdf("robot_000").movable_joints
    positions = [0.25 * (i % 3) for i in range(len(joints))]
    for j, value in zip(joints, positions, strict=True):
        sim.backend.set_joint_angle("robot_000", j.name, value)
    assert sim.frames.transforms("robot_000", positions) == sim.frames.transforms("robot_000")


def test_entity_frames_are_objects_at_their_poses(sim: Simulation) -> None:
    """Every object is a frame 'world -> <name>' at the backend's pose; robots, people (whose link frames are
    computed like a free robot's) and bare agents are not."""
    names = [a.name for a in sim.world.agents if a.kind == "object"]
    people = [a.name for a in sim.world.agents if a.kind == "human"]
    assert people and list(sim.frames.people) == people
    assert sim.frames.moving(people[0])[0] == (WORLD, people[0])  # its feet, at the backend's pose
    assert (f"body_{people[0]}", f"l_y_hip_{people[0]}") in sim.frames.moving(people[0])
    assert sim.frames.static()[f"body_{people[0]}"][0] == people[0]  # the pelvis fixed above the feet
    transforms = sim.frames.entity_transforms()
    assert list(sim.frames.entities) == names == [child for _, child, _, _ in transforms]
    for parent, child, xyz, wxyz in transforms:
        pos, quat = sim.backend.get_pose(child)
        assert parent == WORLD and np.allclose(xyz, pos, atol=0) and np.allclose(wxyz, quat, atol=0)


@pytest.mark.parametrize(("name", "taken"), [("base_link", "link 'base_link' of robot 'bot'"),
                                             ("odom", "the odometry frame of robot 'bot'"),
                                             ("world", "the root frame")])
def test_an_entity_named_like_a_robot_frame_is_refused_at_its_name(name: str, taken: str) -> None:
    """An object whose name is a robot's frame (one robot: a link, odom, map) or 'world' is refused, located."""
    text = SIM_WORLD.read_text().replace('<object name="ball"', f'<object name="{name}"')
    with pytest.raises(WorldError) as err:
        Simulation(parse_world(SIM_WORLD, text), "mujoco")
    issue = err.value.issues[0]
    line = next(i for i, row in enumerate(text.splitlines(), 1) if f'name="{name}"' in row and "<object" in row)
    assert (issue.line, issue.element, issue.attribute) == (line, "object", "name")
    assert f"TF frame '{name}'" in issue.message and taken in issue.message and "rename the object" in issue.message


def test_with_two_robots_frames_are_prefixed_and_a_link_name_is_free() -> None:
    """With two robots every robot frame is '<robot>/<frame>', so an object may be called like a link."""
    text = SIM_WORLD.read_text()
    robot = text[text.index("<robot"):text.index("</robot>") + len("</robot>")]
    text = text.replace(robot, robot + "\n" + robot.replace('name="bot"', 'name="bot2"').replace(
        'pose="0 0 0', 'pose="0 -3 0')).replace('<object name="ball"', '<object name="base_link"')
    sim = Simulation(parse_world(SIM_WORLD, text), "mujoco")
    assert sim.frames.static()["bot2/odom"][0] == WORLD
    assert ("bot2/base_link", "bot2/wheel_l_link") in sim.frames.moving("bot2")
    assert "base_link" in sim.frames.entities


def _urdf(tmp_path: Path, origin: str) -> Path:
    path = tmp_path / "two.urdf"
    path.write_text(f"""<robot name="two"><link name="a"/><link name="b"/>
  <joint name="j" type="revolute"><parent link="a"/><child link="b"/>{origin}<axis xyz="0 0 1"/>
  <limit lower="-1" upper="1"/></joint></robot>""")
    return path


def test_joint_origins_are_read_and_bad_ones_refused_at_their_line(tmp_path: Path) -> None:
    """A joint's <origin xyz rpy> is kept (zeros when absent); anything but 3 finite numbers is refused, located."""
    joint = read_urdf(_urdf(tmp_path, '<origin xyz="0.1 0 0.2" rpy="0 0 1.5"/>')).joints[0]
    assert (joint.origin_xyz, joint.origin_rpy) == ((0.1, 0.0, 0.2), (0.0, 0.0, 1.5))
    assert read_urdf(_urdf(tmp_path, "")).joints[0].origin_xyz == (0.0, 0.0, 0.0)
    for bad in ('xyz="0 0"', 'rpy="0 nan 0"', 'xyz="a b c"'):
        with pytest.raises(UrdfError, match=r"two\.urdf:2: joint 'j': <origin (xyz|rpy)=.*> needs 3 finite numbers"):
            read_urdf(_urdf(tmp_path, f"<origin {bad}/>"))
