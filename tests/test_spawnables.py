"""The spawnables catalogue: the shipped models, a world's own models/, plugins' ones, broken files, the CLI."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

import sigcore
from sigcore import plugins
from sigcore.sim import Simulation
from sigcore.world import Object, Robot, World, parse_world
from sigcore.world.models import Spawnable
from sigcore.world.spawnables import REPOSITORY_MODELS, find_spawnables, parse_element, spawnable

ROOT = Path(__file__).parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"
SHIPPED = {"arm6", "bottle", "box", "can", "sigbot", "table", "trashbox", "wagon"}


@pytest.fixture(autouse=True)
def fresh_registry(fresh_plugins: None) -> None:
    """Each test starts with only the installed plugins, and forgets the in-process ones it added."""


@pytest.fixture(scope="module")
def cleanup() -> World:
    """worlds/cleanup.xml (its models/ folder is the repository's)."""
    return parse_world(CLEANUP)


def _plugin(*items: Spawnable) -> object:
    class Plugin:
        @staticmethod
        @sigcore.hookimpl
        def sigcore_register_spawnables(register: Callable[[Spawnable], None]) -> None:
            for item in items:
                register(item)
    return Plugin()


def _world_with_models(tmp_path: Path, models: dict[str, str]) -> World:
    """A world file in ``tmp_path`` whose models/ folder holds ``{folder: spawnable.xml text}``."""
    for folder, text in models.items():
        (tmp_path / "models" / folder).mkdir(parents=True)
        (tmp_path / "models" / folder / "spawnable.xml").write_text(text)
    (tmp_path / "world.xml").write_text('<world name="w"/>\n')
    return parse_world(tmp_path / "world.xml")


def test_shipped_spawnables_are_listed_with_descriptions_and_bounds(cleanup: World) -> None:
    """Every shipped model is a spawnable of worlds/models, with a description and its bounds."""
    found = {s.name: s for s in find_spawnables(cleanup)}
    assert set(found) == SHIPPED
    for s in found.values():
        assert s.origin == "worlds/models" and s.uri == f"model://{s.name}"
        assert len(s.description) > 20 and s.bounds is not None
        assert Path(s.base) == REPOSITORY_MODELS / s.name
    assert found["box"].bounds == ((-0.05, -0.05, -0.05), (0.05, 0.05, 0.05))
    assert found["table"].bounds == ((-0.6, -0.3, 0.0), (0.6, 0.3, 0.7))
    low, high = found["sigbot"].bounds  # type: ignore[misc]
    assert low[2] == 0.0 and high[2] == pytest.approx(1.4)  # on the floor, 1.40 m tall


def test_every_shipped_spawnable_builds_in_a_world(cleanup: World, tmp_path: Path) -> None:
    """Each shipped element, named and placed in a world file, validates and the MuJoCo backend builds it."""
    lines = []
    for i, s in enumerate(find_spawnables(cleanup)):
        element = s.element.replace(f"<{s.element.split()[0][1:]}",
                                    f'<{s.element.split()[0][1:]} name="{s.name}_0" pose="{3 * i} 0 0.3"', 1)
        for attr in ("urdf", "mesh"):
            element = element.replace(f'{attr}="', f'{attr}="{s.base}/')
        lines.append(element)
    path = tmp_path / "all.xml"
    path.write_text('<world name="all">\n' + "\n".join(lines) + "\n</world>\n")
    sim = Simulation(parse_world(path), "mujoco")
    sim.step(50)
    assert set(sim.entities) == {f"{name}_0" for name in SHIPPED}


def test_sigbot_and_items_match_the_cleanup_world(cleanup: World) -> None:
    """model://sigbot is cleanup.xml's robot_000 (drive, lidar, grippers, arms, gains); can and bottle carry the
    trash items' tags, so the referee scores them."""
    robot, _ = parse_element(spawnable(cleanup, "sigbot").element, REPOSITORY_MODELS / "sigbot" / "x.xml", "r")
    original = cleanup.agent("robot_000")
    assert isinstance(robot, Robot) and isinstance(original, Robot)
    for attr in ("drive", "lidars", "grippers", "arms", "gains", "fixed"):
        assert getattr(robot, attr) == getattr(original, attr), attr
    for name, twin in (("can", "can_0"), ("bottle", "petbottle_1")):
        item, _ = parse_element(spawnable(cleanup, name).element, REPOSITORY_MODELS / name / "x.xml", "i")
        model = cleanup.agent(twin)
        assert isinstance(item, Object) and isinstance(model, Object)
        assert (item.tags, item.size, item.mass, item.graspable) == (model.tags, model.size, model.mass,
                                                                     model.graspable)


def test_element_name_is_optional_and_kept_when_given(tmp_path: Path) -> None:
    """An element without a name gets the one given; one with a name keeps it."""
    unnamed, _ = parse_element('<object shape="sphere" size="0.1"/>', tmp_path / "s.xml", "ball")
    named, _ = parse_element('<!-- c --><object name="mine" shape="sphere" size="0.1"/>', tmp_path / "s.xml", "ball")
    assert (unnamed.name, named.name) == ("ball", "mine")


def test_unknown_spawnable_lists_the_available(cleanup: World) -> None:
    """spawnable() of an unknown name raises KeyError naming it and listing every valid name."""
    with pytest.raises(KeyError, match="no spawnable 'cann'; available: arm6, bottle, box, can, sigbot"):
        spawnable(cleanup, "cann")


BROKEN = {
    "notxml": ('<object shape="box" size="1 1 1"', "not well-formed XML"),
    "wrongtag": ('<world name="x"/>', "<world>; valid: one <robot>, <object> or <human>"),
    "badattr": ('<object shape="box" size="1 1 1" colour="1 0 0 1"/>',
                "1:34: <object> attribute 'colour': unknown attribute"),
    "nofile": ('<object urdf="missing.urdf"/>', "file not found"),
    "two": ('<object shape="sphere" size="1"/>\n<object name="b" shape="sphere" size="1"/>', "2 elements"),
}


def test_broken_spawnable_files_are_skipped_with_a_warning(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A malformed spawnable.xml is left out with a warning naming the file and the problem; the rest load."""
    models = {name: text for name, (text, _) in BROKEN.items()}
    models["good"] = '<object shape="sphere" size="0.05" description="a ball"/>'
    world = _world_with_models(tmp_path, models)
    with caplog.at_level(logging.WARNING, logger="sigcore.spawnables"):
        found = {s.name: s for s in find_spawnables(world)}
    assert found["good"].description == "a ball" and found["good"].origin == str(tmp_path / "models")
    assert not set(BROKEN) & set(found) and SHIPPED <= set(found)
    for name, (_, problem) in BROKEN.items():
        file = tmp_path / "models" / name / "spawnable.xml"
        assert any(str(file) in r.message and problem in r.message for r in caplog.records), name


def test_world_models_come_first(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A world's own models/ folder shadows the repository's model of the same name, with a warning naming both."""
    world = _world_with_models(tmp_path, {"can": '<object shape="box" size="0.1 0.1 0.2" description="my can"/>'})
    with caplog.at_level(logging.WARNING, logger="sigcore.spawnables"):
        can = spawnable(world, "can")
    assert can.description == "my can" and can.base == str(tmp_path / "models" / "can")
    assert any("'can'" in r.message and str(REPOSITORY_MODELS / "can") in r.message and
               str(tmp_path / "models" / "can") in r.message for r in caplog.records)


def test_plugin_registers_spawnables(cleanup: World, tmp_path: Path) -> None:
    """A plugin's spawnables are listed after the folders', with the plugin's name as origin."""
    plugins.register_plugin(_plugin(Spawnable("crate", "a wooden crate", '<object shape="box" size="0.4 0.4 0.3"/>',
                                              str(tmp_path))), name="crates")
    found = {s.name: s for s in find_spawnables(cleanup, plugins.spawnables().values())}
    assert list(found)[-1] == "crate" and found["crate"].origin == "crates"
    assert found["crate"].bounds == ((-0.2, -0.2, -0.15), (0.2, 0.2, 0.15))
    assert plugins.spawnables()["crate"].origin == "crates"
    assert "spawnable crate" in next(i for i in plugins.plugin_infos() if i.name == "crates").provided()


def test_plugin_registering_a_name_twice_is_disabled() -> None:
    """One plugin registering a name twice is refused, the message naming the spawnable and the plugin."""
    item = Spawnable("crate", "a crate", '<object shape="box" size="0.4 0.4 0.3"/>', "")
    with pytest.raises(plugins.PluginLoadError, match="spawnable 'crate' is registered twice by plugin 'dup'"):
        plugins.register_plugin(_plugin(item, item), name="dup")
    with pytest.raises(plugins.PluginLoadError, match="spawnable name '1crate' is invalid"):
        plugins.register_plugin(_plugin(Spawnable("1crate", "", "<object/>", "")), name="badname")


def test_two_plugins_same_name_first_wins_warning_names_both(caplog: pytest.LogCaptureFixture) -> None:
    """A name two plugins register: the first keeps it, a warning names both plugins."""
    item = Spawnable("crate", "a crate", '<object shape="box" size="0.4 0.4 0.3"/>', "")
    plugins.register_plugin(_plugin(item), name="first")
    with caplog.at_level(logging.WARNING, logger="sigcore.plugins"):
        plugins.register_plugin(_plugin(item), name="second")
        assert plugins.spawnables()["crate"].origin == "first"
    assert any("spawnable 'crate'" in r.message and "'second'" in r.message and "'first'" in r.message
               for r in caplog.records)


def test_plugin_spawnable_that_does_not_validate_is_left_out(cleanup: World,
                                                             caplog: pytest.LogCaptureFixture) -> None:
    """A plugin's element that does not validate is left out with a warning naming the plugin and the problem."""
    plugins.register_plugin(_plugin(Spawnable("blob", "?", '<object shape="blob" size="1"/>', "")), name="blobs")
    with caplog.at_level(logging.WARNING, logger="sigcore.spawnables"):
        names = [s.name for s in find_spawnables(cleanup, plugins.spawnables().values())]
    assert "blob" not in names and SHIPPED <= set(names)
    assert any("'blob' of plugin 'blobs'" in r.message and "shape" in r.message for r in caplog.records)


@pytest.mark.slow
def test_cli_lists_spawnables() -> None:
    """`sigcore spawnables WORLD` prints each spawnable's name, origin and description."""
    r = subprocess.run([sys.executable, "-m", "sigcore", "spawnables", str(CLEANUP)], capture_output=True,
                       text=True, cwd=ROOT, timeout=120, env={**os.environ, "COLUMNS": "250"})
    assert r.returncode == 0, r.stderr
    rows = [line for line in r.stdout.splitlines() if "worlds/models" in line]
    assert {row.split("│")[1].strip() for row in rows} == SHIPPED
    assert any("empty drink can" in row for row in rows)
