"""robot_description and /sigcore/scene over ROS 2: latched, received by a node that joins after the start."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from rosproc import start_sim

pytest.importorskip("rclpy")
pytest.importorskip("visualization_msgs")

from sigcore.sim.description import CUBE, CYLINDER, MESH_RESOURCE, SPHERE, robot_description  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

pytestmark = pytest.mark.ros2

DATA = Path(__file__).parent.parent / "data"

WORLD = """<world name="scene" timestep="0.002">
  <robot name="bot" urdf="minibot.urdf">
    <drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.36"/>
  </robot>
  <object name="cube" shape="box" size="0.06 0.08 0.1" pose="0.6 0.5 0.05" color="0.1 0.2 0.3 1"/>
  <object name="ball" shape="sphere" size="0.05" pose="-1 1 0.05" color="0.9 0.8 0.1 0.5"/>
  <object name="can" shape="cylinder" size="0.033 0.12" pose="1 -1 0.06" color="0.8 0.1 0.1 1"/>
  <object name="mug" mesh="mug.obj" scale="1.5" static="true" pose="2 2 0" color="0 0.5 0 1"/>
  <human name="man" pose="-2 -1.5 0"/>
</world>
"""


def test_late_node_receives_robot_description_and_scene(tmp_path: Path) -> None:
    """A node started after the simulation is ready receives /robot_description and /bot/robot_description equal
    to the URDF, /man/robot_description (the person's generated URDF with REP-155 names, no capsule), and a
    MarkerArray with markers for every entity with the world file's sizes and colours."""
    shutil.copy(DATA / "sim" / "minibot.urdf", tmp_path / "minibot.urdf")
    shutil.copy(DATA / "worlds" / "models" / "mug.obj", tmp_path / "mug.obj")
    world = tmp_path / "world.xml"
    world.write_text(WORLD)
    expected = robot_description(parse_world(world), "bot")
    assert expected == (tmp_path / "minibot.urdf").read_text()  # nothing to rewrite: the file as it is
    sim = start_sim(tmp_path, world, "--realtime")
    try:
        r = sim.client("scene.py", "/robot_description", "/bot/robot_description", "/man/robot_description",
                       timeout=90)
    finally:
        sim.stop()
    person = robot_description(parse_world(world), "man")
    assert "<capsule" not in person and 'link name="head_man"' in person and 'joint name="l_knee_man"' in person
    assert r["texts"] == {"/robot_description": [expected], "/bot/robot_description": [expected],
                          "/man/robot_description": [person]}
    assert r["scenes"] == 1
    by_ns: dict[str, list[dict]] = {}
    for m in r["markers"][1:]:
        by_ns.setdefault(m["ns"], []).append(m)
    assert r["markers"][0]["action"] == 3  # DELETEALL first
    assert set(by_ns) == {"bot", "cube", "ball", "can", "mug", "man"}
    assert all(m["frame_locked"] and m["action"] == 0 for ms in by_ns.values() for m in ms)
    approx = pytest.approx
    (cube,) = by_ns["cube"]
    assert (cube["type"], cube["frame"], cube["scale"], cube["color"]) == (
        CUBE, "cube", approx([0.06, 0.08, 0.1]), approx([0.1, 0.2, 0.3, 1.0]))
    (ball,) = by_ns["ball"]
    assert (ball["type"], ball["scale"], ball["color"]) == (SPHERE, approx([0.1] * 3), approx([0.9, 0.8, 0.1, 0.5]))
    (can,) = by_ns["can"]
    assert (can["type"], can["scale"], can["color"]) == (CYLINDER, approx([0.066, 0.066, 0.12]),
                                                         approx([0.8, 0.1, 0.1, 1.0]))
    (mug,) = by_ns["mug"]
    assert (mug["type"], mug["scale"], mug["color"]) == (MESH_RESOURCE, approx([1.5] * 3), approx([0, 0.5, 0, 1]))
    assert mug["mesh_resource"] == f"file://{(tmp_path / 'mug.obj').resolve()}"
    person_types = [m["type"] for m in by_ns["man"]]  # 10 capsules (a cylinder, two spheres), head, hands, feet
    assert (person_types.count(CYLINDER), person_types.count(SPHERE), len(person_types)) == (10, 23, 35)
    assert "head_man" in {m["frame"] for m in by_ns["man"]}
    assert {m["frame"] for m in by_ns["bot"]} == {"base_link", "laser_link"}  # minibot's links with a <visual>
