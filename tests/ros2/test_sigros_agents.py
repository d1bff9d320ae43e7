"""sigros_agents: only the selected agents get the sig_ros <agent>_<suffix> endpoints; the plan agrees."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, start_sim  # noqa: E402
from sigcore_ros2 import Ros2Transport  # noqa: E402

from sigcore.sim import Simulation  # noqa: E402
from sigcore.world import WorldError, parse_world  # noqa: E402

pytestmark = pytest.mark.ros2

AGENTS = ("bot", "cube", "ball", "heavy", "wall", "man", "moderator")


def _world(tmp_path: Path, selection: str) -> Path:
    text = WORLD.read_text().replace('urdf="minibot.urdf"', f'urdf="{WORLD.parent / "minibot.urdf"}"')
    world = tmp_path / "world.xml"
    world.write_text(text.replace('timestep="0.002">', f'timestep="0.002">\n  <plugin name="ros2" '
                                  f'sigros_agents="{selection}"/>', 1))
    return world


def _agents_with_endpoints(names: list[str]) -> set[str]:
    return {a for a in AGENTS for n in names if re.fullmatch(rf"/?{a}_[A-Za-z_]+", n)}


@pytest.mark.parametrize(("selection", "selected"), [
    ("all", set(AGENTS)), ("robots agents", {"bot", "moderator"}), ("tag:trash man", {"cube", "man"}),
    ("objects", {"cube", "ball", "heavy", "wall"}), ("humans heavy", {"man", "heavy"}),
    ("auto", {"bot", "man", "moderator"}), ("auto heavy tag:wall", {"bot", "man", "moderator", "heavy", "wall"}),
])
def test_plan_has_sigros_endpoints_of_the_selected_agents_only(tmp_path: Path, selection: str,
                                                              selected: set[str]) -> None:
    """Ros2Transport.plan lists <agent>_<suffix> endpoints exactly for the agents sigros_agents selects, and the
    idiomatic ones (/bot/odom) whatever the selection."""
    plan = Ros2Transport().plan(Simulation(parse_world(_world(tmp_path, selection))))
    names = [e.name for e in plan]
    assert _agents_with_endpoints(names) == selected
    assert "/bot/odom" in names and "/get_entities" in names


@pytest.mark.parametrize(("selection", "message"), [
    ("robots nobody", "'nobody' is no agent, kind or tag of this world; valid: auto, all, robots, objects, humans, "
                      "agents"),
    ("tag:nothing", "no agent has the tag 'nothing'; tags of this world: furniture, trash, wall"),
    ("all bot", "'all' selects every agent: give it alone"),
    ("", "empty; valid: 'auto', 'all'"),
])
def test_unknown_selection_is_a_located_world_error(tmp_path: Path, selection: str, message: str) -> None:
    """A word naming no agent, kind or tag of the world is refused at the attribute, with the valid ones."""
    with pytest.raises(WorldError) as info:
        Simulation(parse_world(_world(tmp_path, selection)))
    [issue] = info.value.issues
    assert (issue.line, issue.attribute) == (2, "sigros_agents") and message in issue.message, issue


def test_graph_has_the_selected_agents_endpoints_only(tmp_path: Path) -> None:
    """Over ROS 2, sigros_agents="robots agents" leaves every planned endpoint in the graph and no sig_ros
    endpoint of an object or a human."""
    world = _world(tmp_path, "robots agents")
    plan = Ros2Transport().plan(Simulation(parse_world(world)))
    expected = {e.full_name for e in plan if e.kind != "action"}
    sim = start_sim(tmp_path, world, "--realtime")
    try:
        graph = sim.client("graph.py", str(len(expected)))
    finally:
        sim.stop()
    live = set(graph["topics"]) | set(graph["services"])
    assert expected <= live, sorted(expected - live)[:10]
    assert _agents_with_endpoints(sorted(live)) == {"bot", "moderator"}
