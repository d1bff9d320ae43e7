"""The complete example of docs/world-format.md builds and runs on both backends, exactly as written there."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from sigcore.sim import Simulation
from sigcore.world import World, parse_world

ROOT = Path(__file__).parent.parent
DOCS = ROOT / "docs" / "world-format.md"
MODELS = {"sigbot": ROOT / "worlds" / "models" / "sigbot", "table": ROOT / "worlds" / "models" / "table",
          "trashbox": ROOT / "worlds" / "models" / "trashbox",
          "mug.obj": ROOT / "tests" / "data" / "worlds" / "models" / "mug.obj"}
"""What the example's ``models/`` holds: worlds/models/ and a test mesh, as the page says."""


def example_xml() -> str:
    """The XML block under '## A complete example'."""
    text = DOCS.read_text(encoding="utf-8")
    match = re.search(r"^## A complete example.*?```xml\n(.*?)```", text, re.M | re.S)
    assert match is not None, "no xml block under '## A complete example' in docs/world-format.md"
    return match.group(1)


@pytest.fixture(scope="module")
def example(tmp_path_factory: pytest.TempPathFactory) -> World:
    """The example written next to the models it names, parsed."""
    folder = tmp_path_factory.mktemp("example")
    (folder / "models").mkdir()
    for name, target in MODELS.items():
        (folder / "models" / name).symlink_to(target, target_is_directory=target.is_dir())
    (folder / "kitchen.xml").write_text(example_xml(), encoding="utf-8")
    return parse_world(folder / "kitchen.xml")


def test_example_uses_every_element(example: World) -> None:
    """The example shows every element and kind of agent of the format."""
    xml = example_xml()
    for tag in ("world", "plugin", "robot", "drive", "lidar", "gripper", "arm", "gains", "object", "human", "agent"):
        assert f"<{tag} " in xml or f"<{tag}>" in xml, tag
    assert {a.kind for a in example.agents} == {"robot", "object", "human", "agent"}
    shapes = [(o.shape, o.mesh, o.urdf) for o in example.agents if o.kind == "object"]
    assert any(s[0] for s in shapes) and any(s[1] for s in shapes) and any(s[2] for s in shapes)


@pytest.mark.parametrize("backend", ["mujoco", "bullet"])
def test_example_builds_and_runs(example: World, backend: str) -> None:
    """On each backend the example builds with its controller and features, runs 1 s, and stays sane: the robot
    upright on the floor, the can on the table, the referee scoring nothing wrong, every pose finite."""
    sim = Simulation(example, backend)
    assert set(sim.features) == {"referee", "slam"}
    sim.step(round(1.0 / sim.dt))
    assert sim.time == pytest.approx(1.0)
    for name in sim.entities.names:
        pos, quat = sim.backend.get_pose(name)
        assert np.all(np.isfinite(pos)) and np.all(np.isfinite(quat)), name
    robot = sim.robot("robot_000")
    up = robot.rotation()
    assert abs(robot.position()[2]) < 0.05 and 1 - 2 * (up[1] ** 2 + up[2] ** 2) > 0.99  # z axis still up
    assert sim.agent("can_0").position()[2] > 0.7
    referee = sim.features["referee"]
    assert referee.summary()["score"] >= 0  # type: ignore[attr-defined]
