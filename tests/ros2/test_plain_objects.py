"""sigros_agents="auto" (the default): a plain object has no <agent>_<suffix> endpoint of its own, and the shared
/sigcore/sigros/<function> endpoints answer for it by name (issue 28: start-up with thousands of objects)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, start_sim  # noqa: E402
from sigcore_ros2 import Ros2Transport  # noqa: E402
from sigcore_ros2.config import sigros_agents  # noqa: E402

from sigcore.api import api_table  # noqa: E402
from sigcore.sim import Simulation  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

pytestmark = pytest.mark.ros2

PLAIN = ("cube", "ball", "heavy", "wall")
"""The test world's objects: none has a controller."""


def _of(agent: str, names: list[str] | set[str]) -> set[str]:
    """The names that belong to ``agent``: ``<agent>_<suffix>``, ``/<agent>/...``."""
    return {n for n in names if re.fullmatch(rf"/?{agent}(_[A-Za-z_]+|/.*)", n)}


def _shared_names() -> set[str]:
    """What docs/ros2.md documents as the shared endpoints: /sigcore/sigros/<suffix without its underscore> for
    every subscribed or service function whose request has a ``name`` naming the entity."""
    return {f"/sigcore/sigros/{e.suffix[1:]}" for e in api_table() if e.direction != "publish"
            and e.request is not None and "name" in e.request.model_fields and e.ros_type != "SendMsgToSrv"}


def test_plan_gives_plain_objects_no_endpoint_of_their_own() -> None:
    """The default plan has <agent>_<suffix> endpoints for the robot, the human and the bodiless agent, none for
    the four plain objects, and exactly the documented shared endpoints."""
    plan = [e.full_name for e in Ros2Transport().plan(Simulation(parse_world(WORLD)))]
    for agent in ("bot", "man", "moderator"):
        assert _of(agent, plan), agent
    assert all(not _of(obj, plan) for obj in PLAIN), [n for obj in PLAIN for n in _of(obj, plan)]
    assert {n for n in plan if n.startswith("/sigcore/sigros/")} == _shared_names()


def test_shared_endpoints_answer_for_a_plain_object(tmp_path: Path) -> None:
    """Over ROS 2 with the default selection, another process sees every planned endpoint and none of a plain
    object's own; /sigcore/sigros/get_obj_position and get_mass answer for the cube (ground truth from
    get_entity_state), setPosition moves the ball, and an empty or unknown name is refused saying why."""
    plan = {e.full_name for e in Ros2Transport().plan(Simulation(parse_world(WORLD))) if e.kind != "action"}
    sim = start_sim(tmp_path, WORLD, "--paused")
    try:
        out = sim.client("shared.py", str(len(plan)), timeout=120)
    finally:
        sim.stop()
    graph = set(out["graph"])
    assert plan <= graph, sorted(plan - graph)[:10]
    assert _shared_names() <= graph
    assert all(not _of(obj, graph) for obj in PLAIN), [n for obj in PLAIN for n in _of(obj, graph)]
    cube, truth = out["cube"], out["cube_truth"]
    assert cube["success"] is True, cube
    assert [cube["pos_x"], cube["pos_y"], cube["pos_z"]] == pytest.approx([truth["x"], truth["y"], truth["z"]],
                                                                           abs=1e-6)
    assert out["cube_mass"]["success"] is True and out["cube_mass"]["mass"] == pytest.approx(0.2)
    assert out["no_name"]["success"] is False and "'name' must name the entity" in out["no_name"]["message"]
    assert out["unknown"]["success"] is False and "nobody" in out["unknown"]["message"]
    assert out["ball"]["success"] is True
    assert [out["ball"][k] for k in ("pos_x", "pos_y")] == pytest.approx([0.5, -1.5], abs=1e-3)


def test_auto_selects_an_object_with_a_controller(tmp_path: Path) -> None:
    """``auto`` selects an object that has a controller (sig_ros gave endpoints to agents with one), not its plain
    neighbour, and a name added to ``auto`` selects that object too."""
    world = tmp_path / "w.xml"
    world.write_text('<world name="w" timestep="0.002">\n'
                     '  <object name="driven" shape="box" size="0.1 0.1 0.1" pose="0 0 0.05" '
                     'controller="pkg.mod:Ctl"/>\n'
                     '  <object name="plain" shape="box" size="0.1 0.1 0.1" pose="1 0 0.05"/>\n'
                     '  <object name="named" shape="box" size="0.1 0.1 0.1" pose="2 0 0.05"/>\n'
                     '</world>\n')
    parsed = parse_world(world)
    assert sigros_agents(parsed, ("auto",)) == ({"driven"}, None)
    assert sigros_agents(parsed, ("auto", "named")) == ({"driven", "named"}, None)
