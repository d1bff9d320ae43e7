"""The core scene description (sim.scene), robot_description and the /sigcore/scene markers, without ROS."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from sigcore.sim import Simulation
from sigcore.sim.description import CUBE, CYLINDER, DELETEALL, MESH_RESOURCE, SPHERE, robot_description
from sigcore.world import World, parse_world
from sigcore.world.body import SKIN
from sigcore.world.visuals import mesh_vertex_bounds

ROOT = Path(__file__).parent.parent
DATA = Path(__file__).parent / "data"
CLEANUP = ROOT / "worlds" / "cleanup.xml"
BACKENDS = ("mujoco", "bullet")


@pytest.fixture(scope="module")
def cleanup() -> World:
    """The clean-up world (read once for the module)."""
    return parse_world(CLEANUP)


@pytest.fixture(scope="module", params=BACKENDS)
def cleanup_sim(request: pytest.FixtureRequest, cleanup: World) -> Simulation:
    """A simulation of the clean-up world on each backend."""
    return Simulation(cleanup, request.param)


# ------------------------------------------------------------------------------------------------ small worlds
_ROBOT_URDF = """<?xml version="1.0"?>
<!-- a tiny robot with a mesh visual -->
<robot name="tiny">
  <material name="red"><color rgba="1 0 0 1"/></material>
  <link name="base_link">
    <inertial><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry><material name="red"/></visual>
    <visual><geometry><mesh filename="package://tinypkg/meshes/mug.obj" scale="2 2 2"/></geometry></visual>
    <collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision>
  </link>
  <link name="top_link">
    <inertial><mass value="0.1"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="../meshes/mug.obj"/></geometry></visual>
  </link>
  <joint name="top_joint" type="fixed"><parent link="base_link"/><child link="top_link"/>
    <origin xyz="0 0 0.1"/></joint>
  <gazebo reference="base_link"><mu1>0.8</mu1></gazebo>
</robot>
"""

_OBJECT_URDF = """<?xml version="1.0"?>
<robot name="bracket">
  <link name="root_link">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></visual>
    <collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision>
  </link>
  <link name="arm_link">
    <inertial><mass value="0.5"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><origin xyz="0.05 0 0"/><geometry><box size="0.1 0.02 0.04"/></geometry>
      <material name="green"><color rgba="0 1 0 0.5"/></material></visual>
    <collision><origin xyz="0.05 0 0"/><geometry><box size="0.1 0.02 0.04"/></geometry></collision>
  </link>
  <joint name="arm_joint" type="fixed"><parent link="root_link"/><child link="arm_link"/>
    <origin xyz="0.1 0 0.2" rpy="0 0 1.5707963267948966"/></joint>
</robot>
"""


def _tiny_world(tmp: Path, robots: int, extra: str = "") -> Path:
    """A world in ``tmp`` with ``robots`` tiny robots (mesh visuals via package:// and a relative path)."""
    (tmp / "tinypkg" / "meshes").mkdir(parents=True, exist_ok=True)
    (tmp / "tinypkg" / "urdf").mkdir(exist_ok=True)
    shutil.copy(DATA / "worlds" / "models" / "mug.obj", tmp / "tinypkg" / "meshes" / "mug.obj")
    (tmp / "tinypkg" / "urdf" / "tiny.urdf").write_text(_ROBOT_URDF)
    (tmp / "bracket.urdf").write_text(_OBJECT_URDF)
    agents = "".join(f'<robot name="r{i}" urdf="tinypkg/urdf/tiny.urdf" pose="{i} 0 0"/>' for i in range(robots))
    world = tmp / "world.xml"
    world.write_text(f'<world name="tiny">{agents}{extra}</world>')
    return world


# ------------------------------------------------------------------------------------------------ visuals
def test_robot_visuals_come_from_the_urdf_in_link_frames(cleanup_sim: Simulation) -> None:
    """sigbot's 26 <visual> elements are in the scene, each in its link's frame, with the URDF's geometry and
    named materials' colours."""
    robot = cleanup_sim.scene.entities["robot_000"]
    assert robot.kind == "robot" and len(robot.visuals) == 26
    base = [v for v in robot.visuals if v.frame == "base_link"]
    assert [v.shape for v in base] == ["cylinder", "box"]
    assert base[0].size == (0.25, 0.2) and base[0].xyz == (0.0, 0.0, 0.13)
    assert base[0].color == (0.92, 0.92, 0.92, 1.0)  # material "white", defined at robot level
    wheel = next(v for v in robot.visuals if v.frame == "wheel_l_link")
    assert wheel.shape == "cylinder" and wheel.size == (0.1, 0.02) and wheel.color == (0.15, 0.15, 0.15, 1.0)
    assert wheel.wxyz == pytest.approx((math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0), abs=1e-9)
    links = set(cleanup_sim.entities.urdf("robot_000").links)
    assert {v.frame for v in robot.visuals} <= links


def test_primitive_object_visual_is_the_world_files(cleanup_sim: Simulation) -> None:
    """A primitive object has one visual in its own frame with the world file's shape, size and colour."""
    (can,) = cleanup_sim.scene.entities["can_0"].visuals
    assert (can.frame, can.shape, can.size, can.color) == ("can_0", "cylinder", (0.033, 0.12), (0.8, 0.1, 0.1, 1.0))
    assert can.xyz == (0.0, 0.0, 0.0) and can.wxyz == (1.0, 0.0, 0.0, 0.0)


def test_urdf_object_visuals_are_in_the_entity_frame(cleanup_sim: Simulation) -> None:
    """The table's top and four legs are in the frame 'table_0' at their URDF origins, in its material colour."""
    table = cleanup_sim.scene.entities["table_0"]
    assert table.kind == "object" and {v.frame for v in table.visuals} == {"table_0"}
    assert [(v.shape, v.size, v.xyz) for v in table.visuals] == [
        ("box", (1.2, 0.6, 0.04), (0.0, 0.0, 0.68)),
        ("box", (0.05, 0.05, 0.66), (0.55, 0.25, 0.33)), ("box", (0.05, 0.05, 0.66), (0.55, -0.25, 0.33)),
        ("box", (0.05, 0.05, 0.66), (-0.55, 0.25, 0.33)), ("box", (0.05, 0.05, 0.66), (-0.55, -0.25, 0.33))]
    assert {v.color for v in table.visuals} == {(0.6, 0.42, 0.25, 1.0)}


def test_a_person_is_drawn_by_its_links(cleanup_sim: Simulation) -> None:
    """A person's visuals hang on its REP-155 link frames (``head_man_0``...), capsules and spheres from its
    generated URDF; the head sphere reaches its height when the frames are at their standing poses."""
    person = cleanup_sim.scene.entities["man_0"]
    frames = {v.frame for v in person.visuals}
    assert person.kind == "human" and {"body_man_0", "torso_man_0", "head_man_0", "l_knee_man_0",
                                       "r_wrist_man_0"} <= frames
    assert {v.shape for v in person.visuals} == {"capsule", "sphere", "box"}
    head = next(v for v in person.visuals if v.frame == "head_man_0")
    assert head.shape == "sphere" and head.color == SKIN
    parts = cleanup_sim.scene.frame_parts("man_0")
    assert parts["man_0"] is None and parts["head_man_0"] == "head"
    pos, quat = cleanup_sim.backend.get_pose("man_0", "head")
    assert pos[2] + head.xyz[2] + head.size[0] == pytest.approx(1.7, abs=1e-6)
    lo, hi = cleanup_sim.scene.bounds("man_0")
    assert hi[2] == pytest.approx(1.7, abs=1e-6) and lo[2] == pytest.approx(0.0, abs=1e-6)


def test_urdf_object_composes_fixed_joints_and_scale(tmp_path: Path) -> None:
    """A URDF object's child link visual is placed through its fixed joint's origin (rotation included), scaled
    by the world file's scale, and the world file's colour replaces the URDF's when given."""
    extra = ('<object name="b1" urdf="bracket.urdf" static="true" pose="0 1 0"/>'
             '<object name="b2" urdf="bracket.urdf" static="true" scale="2" color="0 0 1 1" pose="0 2 0"/>')
    world = parse_world(_tiny_world(tmp_path, 1, extra))
    sim = Simulation(world, "mujoco")
    one = sim.scene.entities["b1"].visuals[1]
    assert one.xyz == pytest.approx((0.1, 0.05, 0.2)) and one.color == (0.0, 1.0, 0.0, 0.5)
    assert one.wxyz == pytest.approx((math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)))
    two = sim.scene.entities["b2"].visuals[1]
    assert two.xyz == pytest.approx((0.2, 0.1, 0.4)) and two.size == pytest.approx((0.2, 0.04, 0.08))
    assert two.color == (0.0, 0.0, 1.0, 1.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_urdf_object_bounds_follow_its_joints(tmp_path: Path, backend: str) -> None:
    """The bounds of a two-link URDF object are the union of its base box and its rotated arm box, on both
    backends, within 1e-6 m."""
    world = parse_world(_tiny_world(tmp_path, 1, '<object name="b1" urdf="bracket.urdf" static="true" '
                                                 'pose="0 1 0"/>'))
    lo, hi = Simulation(world, backend).scene.bounds("b1")
    # base: x, y in +-0.1, z 0..0.1; arm (yawed 90 deg): x 0.1 +- 0.01, y 1 + 0..0.1, z 0.2 +- 0.02
    assert lo == pytest.approx([-0.1, 0.9, 0.0], abs=1e-6)
    assert hi == pytest.approx([0.11, 1.1, 0.22], abs=1e-6)


# ------------------------------------------------------------------------------------------------ bounds
def test_table_bounds_equal_its_geometry(cleanup_sim: Simulation) -> None:
    """bounds('table_0') is x -2.10..-0.90, y 1.60..2.20, z 0..0.70 (legs on the floor, top 0.66..0.70) within
    1e-6 m."""
    lo, hi = cleanup_sim.scene.bounds("table_0")
    assert lo == pytest.approx([-2.10, 1.60, 0.0], abs=1e-6)
    assert hi == pytest.approx([-0.90, 2.20, 0.70], abs=1e-6)


def test_bounds_follow_the_current_pose(cleanup: World) -> None:
    """After a teleport, the bounds of a can move with it (they are taken at the current poses)."""
    sim = Simulation(cleanup, "mujoco")
    sim.backend.set_pose("can_0", np.array([0.0, 0.0, 1.0]))
    lo, hi = sim.scene.bounds("can_0")
    assert lo == pytest.approx([-0.033, -0.033, 0.94], abs=1e-6)
    assert hi == pytest.approx([0.033, 0.033, 1.06], abs=1e-6)


def test_bounds_of_an_unknown_entity_list_the_names(cleanup_sim: Simulation) -> None:
    """An unknown entity is a KeyError naming the entities."""
    with pytest.raises(KeyError, match="no entity 'tabel_0'; entities: robot_000, .*table_0"):
        cleanup_sim.scene.bounds("tabel_0")


def test_mesh_bounds_are_its_scaled_vertex_box(tmp_path: Path) -> None:
    """A mesh object's bounds are its .obj vertex box times its scale, moved to its pose; an STL reads alike."""
    shutil.copy(DATA / "worlds" / "models" / "mug.obj", tmp_path / "mug.obj")
    world = tmp_path / "w.xml"
    world.write_text('<world><object name="mug" mesh="mug.obj" scale="1.5" static="true" pose="1 2 3"/></world>')
    sim = Simulation(parse_world(world), "mujoco")
    (mug,) = sim.scene.entities["mug"].visuals
    assert mug.shape == "mesh" and mug.mesh == (tmp_path / "mug.obj").resolve() and mug.size == (1.5, 1.5, 1.5)
    lo, hi = sim.scene.bounds("mug")
    assert lo == pytest.approx([1.0, 2.0, 3.0], abs=1e-6)
    assert hi == pytest.approx([1.12, 2.12, 3.15], abs=1e-6)
    triangle = np.array([[0, 0, 0], [1, 0, 0], [0, 2, -1]], dtype="<f4")
    record = np.zeros(1, dtype=[("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    record["v"] = triangle
    (tmp_path / "t.stl").write_bytes(b"solid header".ljust(80) + (1).to_bytes(4, "little") + record.tobytes())
    assert mesh_vertex_bounds(tmp_path / "t.stl") == ((0.0, 0.0, -1.0), (1.0, 2.0, 0.0))


# ------------------------------------------------------------------------------------------------ robot_description
def test_one_robot_description_is_the_urdf_on_both_topics(cleanup: World) -> None:
    """With one robot, /robot_description and /<robot>/robot_description carry the URDF file's text (no mesh
    to rewrite, names unprefixed)."""
    sim = Simulation(cleanup, "mujoco")
    text = (ROOT / "worlds" / "models" / "sigbot" / "sigbot.urdf").read_text()
    for topic in ("/robot_description", "/robot_000/robot_description"):
        publication = sim.publications.get(topic)
        assert (publication.msg_type, publication.qos) == ("std_msgs/msg/String", "latched")
        latest = sim.publications.latest(topic)
        assert latest is not None and latest[1] == {"data": text}


def test_descriptions_have_file_meshes_and_prefixed_names_with_two_robots(tmp_path: Path) -> None:
    """With two robots each description has file:// absolute meshes that exist, link names and joint
    parent/child prefixed '<robot>/', joint names as they are; there is no /robot_description."""
    sim = Simulation(parse_world(_tiny_world(tmp_path, 2)), "mujoco")
    assert "/robot_description" not in {p.topic for p in sim.publications.declared}
    for robot in ("r0", "r1"):
        latest = sim.publications.latest(f"/{robot}/robot_description")
        assert latest is not None
        root = etree.fromstring(latest[1]["data"].encode())
        meshes = [m.get("filename") for m in root.iter("mesh")]
        assert len(meshes) == 2 and all(m.startswith("file:///") and Path(m[7:]).is_file() for m in meshes)
        assert [e.get("name") for e in root.findall("link")] == [f"{robot}/base_link", f"{robot}/top_link"]
        joint = root.find("joint")
        assert joint is not None and joint.get("name") == "top_joint"
        assert (joint.find("parent").get("link"), joint.find("child").get("link")) == (  # type: ignore[union-attr]
            f"{robot}/base_link", f"{robot}/top_link")
        assert root.find("gazebo").get("reference") == f"{robot}/base_link"  # type: ignore[union-attr]
        assert {v.frame for v in sim.scene.entities[robot].visuals} == {f"{robot}/base_link", f"{robot}/top_link"}


def test_one_robot_with_meshes_keeps_its_names(tmp_path: Path) -> None:
    """With one robot, meshes are rewritten to file:// but link names are unchanged; the shared URDF document is
    not modified."""
    world = parse_world(_tiny_world(tmp_path, 1))
    text = robot_description(world, "r0")
    root = etree.fromstring(text.encode())
    assert [e.get("name") for e in root.findall("link")] == ["base_link", "top_link"]
    assert all(m.get("filename", "").startswith("file:///") for m in root.iter("mesh"))
    assert world.urdf("r0").root.find("link/visual/geometry/mesh").get("filename").startswith("package://")  # type: ignore[union-attr]


# ------------------------------------------------------------------------------------------------ markers
def _markers(sim: Simulation) -> list[dict]:
    latest = sim.publications.latest("/sigcore/scene")
    assert latest is not None
    return latest[1]["markers"]


def test_scene_markers_carry_the_world_files_sizes_and_colours(cleanup: World) -> None:
    """/sigcore/scene starts with DELETEALL and has markers for every entity: a primitive's size and colour, the
    table's five cubes, a human's capsule as a cylinder and two spheres, all frame-locked in their frames."""
    sim = Simulation(cleanup, "mujoco")
    publication = sim.publications.get("/sigcore/scene")
    assert (publication.msg_type, publication.qos) == ("visualization_msgs/msg/MarkerArray", "latched")
    markers = _markers(sim)
    assert markers[0]["action"] == DELETEALL
    by_ns: dict[str, list[dict]] = {}
    for m in markers[1:]:
        by_ns.setdefault(m["ns"], []).append(m)
    assert set(by_ns) == {e.name for e in cleanup.entities}
    assert all(m["frame_locked"] and [x["id"] for x in ms] == list(range(len(ms)))
               for ms in by_ns.values() for m in ms)
    (can,) = by_ns["can_0"]
    assert (can["type"], can["header"]["frame_id"]) == (CYLINDER, "can_0")
    assert can["scale"] == {"x": 0.066, "y": 0.066, "z": 0.12}
    assert can["color"] == {"r": 0.8, "g": 0.1, "b": 0.1, "a": 1.0}
    (wall, ) = by_ns["wall_north"]
    assert wall["type"] == CUBE and wall["scale"] == {"x": 10.2, "y": 0.1, "z": 1.0}
    assert [m["type"] for m in by_ns["table_0"]] == [CUBE] * 5
    person = [m["type"] for m in by_ns["man_0"]]  # 10 capsules (a cylinder and two spheres), head, hands, feet
    assert (person.count(CYLINDER), person.count(SPHERE), person.count(CUBE), len(person)) == (10, 23, 2, 35)
    assert "head_man_0" in {m["header"]["frame_id"] for m in by_ns["man_0"]}
    assert len(by_ns["robot_000"]) == 26 and by_ns["robot_000"][0]["header"]["frame_id"] == "base_link"


def test_mesh_markers_and_changed_republishes(tmp_path: Path) -> None:
    """A mesh visual is a MESH_RESOURCE marker with a file:// URI and its own colour; Scene.changed() bumps the
    version and republishes the markers."""
    sim = Simulation(parse_world(_tiny_world(tmp_path, 1)), "mujoco")
    mesh = [m for m in _markers(sim) if m.get("type") == MESH_RESOURCE]
    assert len(mesh) == 2 and all(m["mesh_resource"].startswith("file:///") and
                                  not m["mesh_use_embedded_materials"] for m in mesh)
    assert mesh[0]["scale"] == {"x": 2.0, "y": 2.0, "z": 2.0}
    before = sim.scene.version
    del sim.scene.entities["r0"]
    sim.scene.changed()
    assert sim.scene.version == before + 1 and [m.get("ns") for m in _markers(sim)] == [None]
