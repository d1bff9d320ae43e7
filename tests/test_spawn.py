"""Spawning and deleting while running, through the core (``Simulation.spawn`` / ``delete``), on both backends."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trackers

from sigcore.agent.exceptions import ApiError
from sigcore.sim import Simulation
from sigcore.sim.spawn import EntityChange
from sigcore.world import parse_world
from sigcore.world.exceptions import SpawnRefusal
from sigcore.world.resources import SpawnRequest

ROOT = Path(__file__).resolve().parents[1]
SIGBOT = ROOT / "worlds" / "models" / "sigbot" / "sigbot.urdf"
BACKENDS = ["mujoco", "bullet"]

WORLD = """<world name="small" timestep="0.002">
  <robot name="robot_000" urdf="{sigbot}" pose="0 0 0 0 0 0">
    <drive type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"/>
    <gripper part="l_hand_link" grasp_radius="0.3"/>
  </robot>
  <object name="cube" shape="box" size="0.1 0.1 0.1" mass="0.2" graspable="true" pose="2 0 0.05"/>
  <object name="table" shape="box" size="0.6 0.6 0.4" static="true" pose="-2 0 0.2"/>
  <object name="plate" shape="box" size="0.2 0.2 0.04" mass="0.3" pose="-2 0 0.421"/>
</world>
"""

BOX = '<object shape="box" size="0.1 0.1 0.1" mass="0.2" tags="trash can"/>'
SIGBOT_ELEMENT = f"""<robot urdf="{SIGBOT}">
  <drive type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"/>
  <lidar name="base_scan" link="base_laser_link" beams="36" rate="10"/>
</robot>"""


@pytest.fixture(params=BACKENDS)
def sim(request: pytest.FixtureRequest, tmp_path: Path) -> Simulation:
    path = tmp_path / "small.xml"
    path.write_text(WORLD.format(sigbot=SIGBOT))
    return Simulation(parse_world(path), backend=request.param)


def _one(sim: Simulation, **kw: object) -> str:
    [result] = sim.entities.spawn([SpawnRequest(**kw)])  # type: ignore[arg-type]
    assert isinstance(result, str), result
    return result


def test_spawned_box_falls_rests_and_is_everywhere(sim: Simulation) -> None:
    """A box spawned in the air while running falls to rest on the floor and is in every core view."""
    sim.step(10)
    changes: list[EntityChange] = []
    sim.events.subscribe("entities", changes.append)
    name = _one(sim, name="box_a", resource=BOX, xyz=(1.0, 1.0, 0.5))
    assert name == "box_a" and changes == [EntityChange(added=("box_a",))]
    assert "box_a" in sim.entities and "box_a" in sim.entities.names and sim.entities.spawned == {"box_a": ""}
    assert "box_a" in sim.scene.entities and "box_a" in sim.frames.entities
    assert sim.entities.info.get("box_a").tags == ("trash", "can")
    assert any(p.topic == "box_a_onRecvMsg" for p in sim.publications.declared)
    sim.step(750)
    pos, _ = sim.backend.get_pose("box_a")
    assert pos[2] == pytest.approx(0.05, abs=0.01)  # resting on the floor: half its height, 1 cm margin
    assert np.linalg.norm(sim.backend.get_velocity("box_a")[0]) < 0.01


def test_others_unchanged_by_a_spawn(sim: Simulation) -> None:
    """Every other entity's pose right after a spawn is exactly its pose before it."""
    sim.step(50)
    before = sim.poses()
    _one(sim, resource=BOX, name="far", xyz=(8.0, 8.0, 0.3))
    after = sim.poses()
    for name, (pos, quat) in before.items():
        assert np.array_equal(pos, after[name][0]) and np.array_equal(quat, after[name][1]), name


def test_spawned_robot_is_a_full_agent(sim: Simulation) -> None:
    """A robot spawned with a world-format element gets its drive, lidar, frames, publications and controller."""
    trackers.CALLS.clear()
    sim.step(5)
    element = SIGBOT_ELEMENT.replace("<robot ", '<robot controller="trackers:Tracker" ')
    name = _one(sim, name="robot_001", resource=element, xyz=(0.0, 2.0, 0.3))
    robot = sim.robot(name)
    assert sim.entities.drive(name).geometry() == (0.1, 0.4)
    assert [lidar.robot for lidar in sim.entities.lidars] == ["robot_001"]
    assert sim.frames.prefix("robot_001") == "robot_001/"  # robot_000 keeps its unprefixed frames
    assert sim.frames.prefix("robot_000") == ""
    assert sim.frames.static()["robot_001/odom"][0] == "world"
    topics = {p.topic for p in sim.publications.declared}
    assert {"robot_001_scan", "/robot_001/robot_description"} <= topics
    assert [c for a, c, _ in trackers.CALLS if a == name] == ["on_init"]
    sim.step(round(0.3 / sim.dt))
    assert [c for a, c, _ in trackers.CALLS if a == name].count("on_action") >= 3
    assert robot.name == name
    sim.step(500)
    pos, _ = sim.backend.get_pose(name)
    assert abs(pos[2]) < 0.1  # on the floor


def test_delete_releases_grasp_and_forgets_everything(sim: Simulation) -> None:
    """Deleting a grasped object releases the grasp; the entity leaves every core view and its topics go."""
    robot = sim.robot("robot_000")
    sim.backend.set_pose("cube", np.array([0.0, 0.0, 0.6]))
    hand = sim.backend.get_pose("robot_000", "l_hand_link")[0]
    sim.backend.set_pose("cube", hand)
    robot.grasp("l_hand_link", "cube")
    assert sim.entities.grasps.held_by("cube") is not None
    changes: list[EntityChange] = []
    sim.events.subscribe("entities", changes.append)
    sim.entities.delete(["cube"])
    assert changes == [EntityChange(removed=("cube",))]
    assert sim.entities.grasps.items() == []
    for view in (sim.entities, sim.entities.names, sim.scene.entities, sim.frames.entities, sim.entities.graspable):
        assert "cube" not in view
    assert not any(p.agent == "cube" for p in sim.publications.declared)
    with pytest.raises(ApiError):
        sim.backend.get_pose("cube")
    sim.step(100)  # the simulation goes on


def test_deleting_a_support_lets_things_fall(sim: Simulation) -> None:
    """Deleting a static table lets the plate that rested on it fall to the floor."""
    sim.step(100)
    assert sim.backend.get_pose("plate")[0][2] == pytest.approx(0.42, abs=0.01)
    sim.entities.delete(["table"])
    sim.step(600)
    assert sim.backend.get_pose("plate")[0][2] == pytest.approx(0.02, abs=0.01)


def test_refusals_name_the_problem(sim: Simulation, tmp_path: Path) -> None:
    """Each bad request is refused with its code and a message naming what was wrong; nothing changes."""
    bad_joint = tmp_path / "bad_joint.urdf"
    bad_joint.write_text('<robot name="b"><link name="a"/><link name="c"/>'
                         '<joint name="j" type="spherical"><parent link="a"/><child link="c"/></joint></robot>')
    cases = [
        (SpawnRequest(name="x", resource="<robot name='r'><link name='a'></robot>"), "RESOURCE_PARSE_ERROR",
         "well-formed"),
        (SpawnRequest(name="x", uri="model://no_such_model"), "NOT_FOUND", "no_such_model"),
        (SpawnRequest(name="cube", resource=BOX), "NAME_NOT_UNIQUE", "cube"),
        (SpawnRequest(name="9lives", resource=BOX), "NAME_INVALID", "9lives"),
        (SpawnRequest(name="x", resource=BOX, xyz=(float("nan"), 0.0, 1.0)), "INVALID_POSE", "finite"),
        (SpawnRequest(name="x", resource=BOX, wxyz=(0.0, 0.0, 0.0, 0.0)), "INVALID_POSE", "length 0"),
        (SpawnRequest(name="x", resource='<object mesh="/nope/missing.obj"/>'), "MISSING_ASSETS", "missing.obj"),
        (SpawnRequest(name="x", uri=str(bad_joint)), "RESOURCE_PARSE_ERROR", "spherical"),
        (SpawnRequest(name="x", resource='<robot name="f"><link name="a"/><link name="c"/><joint name="j" '
                                          'type="floating"><parent link="a"/><child link="c"/></joint></robot>'),
         "RESOURCE_PARSE_ERROR", "floating"),
        (SpawnRequest(name="x", resource='<robot name="s"><link name="a"/><link name="c"/><joint name="j" '
                                          'type="ball"><parent link="a"/><child link="c"/></joint></robot>'),
         "RESOURCE_PARSE_ERROR", "resource:1: joint 'j' has type 'ball'"),
        (SpawnRequest(name="x"), "NO_RESOURCE", "empty"),
        (SpawnRequest(name="x", resource="<sdf/>"), "UNSUPPORTED_FORMAT", "<sdf>"),
        (SpawnRequest(name="x", resource=BOX, namespace="bad ns"), "NAMESPACE_INVALID", "bad ns"),
        (SpawnRequest(name="x", resource=BOX, frame="nowhere"), "INVALID_POSE", "nowhere"),
        (SpawnRequest(name="x", resource='<object shape="box" size="0.1 0.1"/>'), "RESOURCE_PARSE_ERROR", "size"),
    ]
    before = sim.poses()
    names = list(sim.entities)
    results = sim.entities.spawn([request for request, _, _ in cases])
    for (request, code, word), result in zip(cases, results, strict=True):
        assert isinstance(result, SpawnRefusal), request
        assert result.code == code, (request, str(result))
        assert word in str(result), (request, str(result))
    assert list(sim.entities) == names
    after = sim.poses()
    assert all(np.array_equal(before[n][0], after[n][0]) for n in before)
    sim.step(10)


def test_renaming_and_batches(sim: Simulation) -> None:
    """allow_renaming picks a free name; valid requests of a batch are spawned even when others are refused."""
    results = sim.entities.spawn([SpawnRequest(name="cube", resource=BOX, allow_renaming=True, xyz=(3.0, 3.0, 0.1)),
                         SpawnRequest(name="cube", resource=BOX, allow_renaming=True, xyz=(3.5, 3.0, 0.1)),
                         SpawnRequest(name="cube", resource=BOX, xyz=(4.0, 3.0, 0.1))])
    assert results[:2] == ["cube_1", "cube_2"]
    assert isinstance(results[2], SpawnRefusal) and results[2].code == "NAME_NOT_UNIQUE"
    assert {"cube_1", "cube_2"} <= set(sim.entities)


def test_pose_relative_to_an_entity(sim: Simulation) -> None:
    """A pose in an entity's frame is composed with that entity's pose."""
    name = _one(sim, name="on_table", resource=BOX, xyz=(0.0, 0.0, 0.5), frame="table")
    pos, _ = sim.backend.get_pose(name)
    assert pos == pytest.approx([-2.0, 0.0, 0.7], abs=1e-6)


def test_reset_despawns_and_restores(sim: Simulation) -> None:
    """A full reset deletes spawned entities and brings back deleted ones; a state reset keeps spawned ones."""
    _one(sim, name="extra", resource=BOX, xyz=(1.0, -1.0, 0.3))
    sim.step(50)
    sim.reset(despawn=False)
    assert "extra" in sim.entities
    assert sim.backend.get_pose("extra")[0] == pytest.approx([1.0, -1.0, 0.3], abs=1e-6)
    sim.entities.delete(["plate"])
    sim.reset()
    assert "extra" not in sim.entities and "plate" in sim.entities and sim.entities.spawned == {}
    assert sim.backend.get_pose("plate")[0] == pytest.approx([-2.0, 0.0, 0.421], abs=1e-6)
    sim.step(10)


def test_delete_unknown_is_refused(sim: Simulation) -> None:
    """Deleting a name that is no entity is NOT_FOUND, listing the entities."""
    with pytest.raises(SpawnRefusal) as info:
        sim.entities.delete(["ghost"])
    assert info.value.code == "NOT_FOUND" and "cube" in str(info.value)
