"""Feature configuration validated by the core: every <plugin> attribute problem located at file:line:column."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from sigcore import plugins
from sigcore.sim import Simulation
from sigcore.world import WorldError, WorldIssue, parse_world
from sigcore.world.plugin_config import validate_plugin

ROOT = Path(__file__).parent.parent
SIM_DATA = ROOT / "tests" / "data" / "sim"
BUNDLED = ("ik", "slam", "referee", "ros2")

# one world, every bundled feature with bad attributes; (line, column, attribute, words of the message) below
BAD = """\
<world name="t" timestep="0.002">
  <plugin name="ik" speed="2" max_joint_speed="fast"/>
  <plugin name="slam" voxel_size="abc" refine="maybe"/>
  <plugin name="referee" corect_box="1" wrong_box="minus" floor="maybe"/>
  <plugin name="ros2" clock_rte="1" state_rate="often" sigros="nope"/>
  <robot name="bot" urdf="{urdf}">
    <drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.36"/>
    <lidar name="scan" link="laser_link" beams="180" range="0.05 8" rate="10"/>
  </robot>
</world>
"""
EXPECTED = [
    (2, 21, "speed", ("unknown attribute of plugin 'ik'", "valid: name, agent, max_joint_speed")),
    (2, 31, "max_joint_speed", ("'fast' is not a number", "valid: a number, 0 < max_joint_speed <= 100 [rad/s]")),
    (3, 3, None, ("required attribute 'agent' is missing",)),
    (3, 23, "voxel_size", ("'abc' is not a number", "0 < voxel_size <= 5 [m]")),
    (3, 40, "refine", ("'maybe' is not a boolean; valid: true, false",)),
    (4, 26, "corect_box", ("(did you mean 'correct_box'?)", "valid: name, rules, service, correct_box")),
    (4, 41, "wrong_box", ("'minus' is not an integer; valid: an integer [points]",)),
    (4, 59, "floor", ("'maybe' is not a boolean; valid: true, false",)),
    (5, 23, "clock_rte", ("(did you mean 'clock_rate'?)", "valid: name, clock_rate, clock_wall_limit, state_rate")),
    (5, 37, "state_rate", ("'often' is not a number", "state_rate > 0 [Hz]")),
    (5, 56, "sigros", ("'nope' is not a boolean",)),
]


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "world.xml"
    path.write_text(text.format(urdf=SIM_DATA / "minibot.urdf"))
    return path


def _located(issues: list[WorldIssue]) -> list[tuple[int, int, str | None]]:
    return [(i.line, i.column, i.attribute) for i in issues]


@pytest.fixture(scope="module")
def bad_world(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The world with a bad attribute of each kind in each bundled feature."""
    return _write(tmp_path_factory.mktemp("bad"), BAD)


def test_bundled_features_declare_strict_frozen_config_models() -> None:
    """Each bundled feature declares a config model that forbids unknown fields and is frozen."""
    for name in BUNDLED:
        model = plugins.get_feature(name).config_model
        assert model.model_config.get("extra") == "forbid" and model.model_config.get("frozen") is True, name


def test_every_problem_is_located_at_its_attribute(bad_world: Path) -> None:
    """Unknown attributes, bad numbers and booleans and a missing required one come out at their line:column."""
    with pytest.raises(WorldError) as info:
        Simulation(parse_world(bad_world), "mujoco")
    issues = info.value.issues
    assert _located(issues) == [(line, col, attr) for line, col, attr, _ in EXPECTED]
    for issue, (_, _, _, words) in zip(issues, EXPECTED, strict=True):
        assert issue.file == bad_world and issue.element == "plugin"
        for word in words:
            assert word in issue.message, (word, str(issue))
    assert str(issues[0]).startswith(f"{bad_world}:2:21: <plugin> attribute 'speed': unknown attribute")


@pytest.mark.slow
def test_sigcore_check_reports_them(bad_world: Path) -> None:
    """`sigcore check` prints the same located problems, one per line, exit code 2, no traceback."""
    r = subprocess.run([sys.executable, "-m", "sigcore", "check", str(bad_world)], capture_output=True, text=True,
                       cwd=ROOT, timeout=120)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    lines = [line for line in r.stderr.splitlines() if line.startswith(str(bad_world))]
    assert [tuple(int(n) for n in line.split(":")[1:3]) for line in lines] == [(ln, c) for ln, c, _, _ in EXPECTED]


@pytest.mark.parametrize(("plugin", "where", "words"), [
    ('<plugin name="ik" agent="bot ghost"/>', (2, 21, "agent"), "'ghost' is not a robot of the world; robots: bot"),
    ('<plugin name="slam" agent="cube"/>', (2, 23, "agent"), "'cube' is not a robot of this world; robots: bot"),
    ('<plugin name="slam" agent="bot" lidar="front"/>', (2, 35, "lidar"), "has no lidar 'front'; lidars: scan"),
    ('<plugin name="referee" rules="cleanup" robots="cube"/>', (2, 42, "robots"), "'cube' is not a robot"),
])
def test_checks_that_need_the_world_are_located_too(tmp_path: Path, plugin: str,
                                                     where: tuple[int, int, str], words: str) -> None:
    """A feature's own check against the world (a FieldError) is reported at the attribute it names."""
    text = BAD.splitlines()
    body = "\n".join([text[0], f"  {plugin}", *text[5:]]) + "\n"
    with pytest.raises(WorldError) as info:
        Simulation(parse_world(_write(tmp_path, body)), "mujoco")
    [issue] = info.value.issues
    assert (issue.line, issue.column, issue.attribute) == where and words in issue.message


def test_unknown_feature_is_located_at_its_name(tmp_path: Path) -> None:
    """A <plugin> naming no registered feature is reported at its name attribute with the registered ones."""
    path = _write(tmp_path, '<world name="t">\n  <plugin  name="slma"/>\n</world>\n')
    with pytest.raises(WorldError) as info:
        Simulation(parse_world(path), "mujoco")
    [issue] = info.value.issues
    assert (issue.line, issue.column, issue.attribute) == (2, 12, "name") and "did you mean 'slam'" in issue.message


def _worlds() -> list[Path]:
    found = sorted((ROOT / "worlds").glob("*.xml")) + sorted((ROOT / "tests").rglob("*.xml"))
    return [p for p in found if "<plugin" in p.read_text() and "/bad/" not in p.as_posix()]


@pytest.mark.parametrize("world_file", _worlds(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_world_with_plugins_still_validates(world_file: Path) -> None:
    """Every world under worlds/ and tests/ (except the deliberately bad ones) passes its features' models."""
    world = parse_world(world_file)
    assert world.plugins
    for element in world.plugins:
        config = validate_plugin(world, element, plugins.get_feature(element.name).config_model)
        assert set(config.model_fields_set) == set(element.config)


def test_validated_config_reaches_the_feature(tmp_path: Path) -> None:
    """The feature receives the validated model: strings parsed to numbers, booleans and lists."""
    body = BAD.splitlines()
    plugin = '  <plugin name="referee" correct_box="+500" floor="false" collision_tags="wall  sofa" time_limit="9.5"/>'
    path = _write(tmp_path, "\n".join([body[0], plugin, *body[5:]]) + "\n")
    sim = Simulation(parse_world(path), "mujoco")
    config = sim.features["referee"].config  # type: ignore[attr-defined]
    assert (config.correct_box, config.floor, config.collision_tags, config.time_limit) == (
        500, False, ("wall", "sofa"), 9.5)
