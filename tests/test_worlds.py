"""Worlds at run time through the core: the catalogue (``sigcore.world.catalogue``), ``sim.worlds.load`` and
``unload_world`` on both backends, and their refusals."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import sigcore
from sigcore import plugins
from sigcore.agent.exceptions import ApiError
from sigcore.feature import Feature
from sigcore.publish import Publication, PublicationSink
from sigcore.sim import Simulation, run
from sigcore.sim.spawn import WorldChange
from sigcore.transport import Transport
from sigcore.world import parse_world
from sigcore.world.catalogue import WORLDS_DIR, default_sources, find_worlds, matches, open_world
from sigcore.world.exceptions import SpawnRefusal, WorldError, WorldRefusal
from sigcore.world.models import World
from sigcore.world.resources import SpawnRequest

ROOT = Path(__file__).resolve().parents[1]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
ARM6 = ROOT / "worlds" / "arm6.xml"
SIGBOT = ROOT / "worlds" / "models" / "sigbot" / "sigbot.urdf"
BACKENDS = ["mujoco", "bullet"]

SMALL = """<world name="small" timestep="0.004" description="a box on the floor" tags="test tiny">
  <object name="crate" shape="box" size="0.2 0.2 0.2" mass="1" pose="0 0 0.5" tags="box"/>
</world>
"""


class Recorder(PublicationSink):
    """A sink that keeps the topics declared and withdrawn, in order."""

    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def declare(self, publication: Publication) -> None:
        self.events.append(("declare", publication.topic))

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        pass

    def withdraw(self, publication: Publication) -> None:
        self.events.append(("withdraw", publication.topic))


@pytest.fixture(scope="module")
def cleanup() -> World:
    return parse_world(CLEANUP)


@pytest.fixture(scope="module")
def arm6() -> World:
    return parse_world(ARM6)


def _catalogue() -> list[Any]:
    return find_worlds(default_sources([], registered=plugins.worlds()))[0]  # as the simulation passes them


# ------------------------------------------------------------------ the catalogue
def test_catalogue_lists_the_shipped_worlds_with_descriptions_and_tags() -> None:
    """worlds/ contributes cleanup and arm6, each with its <world> name, description, tags and file URI."""
    found = {w.name: w for w in _catalogue()}
    assert {"cleanup", "arm6"} <= set(found)
    assert found["cleanup"].path == CLEANUP and found["cleanup"].uri == CLEANUP.as_uri()
    assert found["cleanup"].tags == ("indoor", "home", "robocup") and "clean-up" in found["cleanup"].description
    assert found["arm6"].source == "worlds/" and "ik" in found["arm6"].tags
    assert matches(found["cleanup"], ["indoor", "home"], True) and not matches(found["arm6"], ["indoor"], False)
    assert matches(found["arm6"], ["indoor", "ik"], False) and matches(found["arm6"], [], True)


def test_catalogue_sources_files_folders_and_problems(tmp_path: Path) -> None:
    """A folder gives its <world> files only; a file is listed once; a missing path or a non-world file is a
    problem naming it; the current world comes first."""
    (tmp_path / "small.xml").write_text(SMALL)
    (tmp_path / "notes.xml").write_text("<notes/>")
    (tmp_path / "broken.xml").write_text("<world")
    not_world = tmp_path / "sdf.sdf"
    not_world.write_text("<sdf/>")
    found, problems = find_worlds(default_sources([CLEANUP], [tmp_path, tmp_path / "small.xml",
                                                              tmp_path / "gone", not_world]))
    names = [w.name for w in found]
    assert names[0] == "cleanup" and found[0].source == "current"
    assert names.count("cleanup") == 1 and names.count("small") == 1 and "notes" not in names
    small = next(w for w in found if w.name == "small")
    assert small.source == "command line" and small.tags == ("test", "tiny")
    assert len(problems) == 2
    assert any(str(tmp_path / "gone") in p and "no such file" in p for p in problems)
    assert any(str(not_world) in p and "<world>" in p for p in problems)
    [problem] = find_worlds([(tmp_path / ("x" * 5000), "request")])[1]
    assert "no such file or folder" in problem and len(problem) < 400


@pytest.mark.usefixtures("fresh_plugins")
def test_plugin_registers_worlds(tmp_path: Path) -> None:
    """A plugin's world folder is listed with the plugin's name as source; registering a path twice is refused."""
    (tmp_path / "small.xml").write_text(SMALL)

    def plugin(*paths: Path) -> object:
        class Plugin:
            @staticmethod
            @sigcore.hookimpl
            def sigcore_register_worlds(register: Callable[[Path], None]) -> None:
                for path in paths:
                    register(path)
        return Plugin()

    plugins.register_plugin(plugin(tmp_path), name="extra_worlds")
    found = {w.name: w for w in _catalogue()}
    assert found["small"].source == "plugin extra_worlds" and found["small"].path == tmp_path / "small.xml"
    with pytest.raises(plugins.PluginLoadError, match="registered twice by plugin 'twice'"):
        plugins.register_plugin(plugin(tmp_path, tmp_path), name="twice")


def test_world_description_and_tags_are_validated(tmp_path: Path) -> None:
    """<world description> and tags are checked like an entity's: a bad tag is located at the <world> element."""
    path = tmp_path / "w.xml"
    path.write_text('<world tags="ok bad\x7ftag"/>')
    with pytest.raises(WorldError) as e:
        parse_world(path)
    assert e.value.issues[0].line == 1 and e.value.issues[0].attribute == "tags"
    path.write_text(f'<world description="{"x" * 501}"/>')
    with pytest.raises(WorldError, match="description"):
        parse_world(path)


@pytest.mark.parametrize(("uri", "text", "code", "says"), [
    ("", "", "NO_RESOURCE", "neither uri nor resource_string"),
    ("", "   ", "NO_RESOURCE", "neither uri nor resource_string"),
    ("no_such_world", "", "NOT_FOUND", "cleanup"),
    ("file:///nonexistent/w.xml", "", "NOT_FOUND", "file:///nonexistent/w.xml"),
    ("", "<sdf version='1.9'><world name='w'/></sdf>", "UNSUPPORTED_FORMAT", "<sdf>"),
    ("", "<mujoco/>", "UNSUPPORTED_FORMAT", "<mujoco>"),
    ("", "<world><object name='a'", "RESOURCE_PARSE_ERROR", "not well-formed"),
    ("", "<world><object name='a' shape='box' size='1 1' mass='1'/></world>", "RESOURCE_PARSE_ERROR", "size"),
    ("", "<world><robot name='r' urdf='/nonexistent/r.urdf'/></world>", "MISSING_ASSETS", "file not found"),
    ("", "<world><light name='sun'/></world>", "UNSUPPORTED_ELEMENTS", "unknown element"),
    ("w" * 5000, "", "NOT_FOUND", "no world file"),  # a name the operating system refuses to look up
    ("package://sigcore/" + "w" * 5000, "", "NOT_FOUND", "no world file"),
])
def test_open_world_refusals(uri: str, text: str, code: str, says: str) -> None:
    """Each bad world request is refused with the standard code and a message naming what was wrong."""
    with pytest.raises(WorldRefusal) as e:
        open_world(uri, text, _catalogue())
    assert e.value.code == code and says in str(e.value)


def test_open_world_by_name_path_uri_and_text(tmp_path: Path) -> None:
    """A world is named by its catalogue name, its file stem, a path, a file:// or package://sigcore/ URI, or
    given as text (its name and tags parsed)."""
    catalogue = _catalogue()
    for uri in ("cleanup", "cleanup.xml", str(CLEANUP), CLEANUP.as_uri(), "package://sigcore/worlds/cleanup.xml"):
        assert open_world(uri, "", catalogue).source == CLEANUP, uri
    world = open_world("", SMALL, catalogue)
    assert world.name == "small" and world.tags == ("test", "tiny") and world.timestep == 0.004


# ------------------------------------------------------------------ load and unload
@pytest.mark.parametrize("backend", BACKENDS)
def test_loaded_world_runs_as_a_fresh_one(backend: str, cleanup: World, arm6: World) -> None:
    """A world loaded into a running simulation starts paused at step 0 and then evolves exactly as a new
    Simulation of it (bitwise), and the run's elapsed steps and time go on."""
    sim = Simulation(cleanup, backend)
    sim.step(120)
    sim.worlds.load(arm6)
    assert sim.worlds.loaded and sim.world is arm6 and sim.step_count == 0 and sim.control.paused
    assert list(sim.entities.names) == ["arm_0"] and list(sim.entities) == ["arm_0"] and list(sim.features) == ["ik"]
    sim.step(200)
    fresh = Simulation(arm6, backend)
    fresh.step(200)
    assert np.array_equal(sim.backend.get_pose("arm_0", "tool0")[0], fresh.backend.get_pose("arm_0", "tool0")[0])
    assert sim.worlds.elapsed_steps == 320 and sim.worlds.elapsed_time == pytest.approx(0.64, abs=1e-12)
    assert sim.time == pytest.approx(0.4, abs=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_reloading_the_same_world_starts_it_over(backend: str, cleanup: World) -> None:
    """Loading the running world again restores it: trash back in place, spawned entities gone, the referee new."""
    sim = Simulation(cleanup, backend)
    start = sim.poses()
    [name] = sim.entities.spawn([SpawnRequest(name="extra", xyz=(0.0, 0.0, 0.5),
                                              resource='<object shape="box" size="0.1 0.1 0.1" mass="1"/>')])
    assert name == "extra"
    sim.agent("can_0").set_position((1.0, 1.0, 1.0))
    sim.step(50)
    old_referee = sim.features["referee"]
    sim.worlds.load(cleanup)
    assert "extra" not in sim.entities.names and sim.entities.spawned == {}
    assert sim.features["referee"] is not old_referee
    assert all(np.array_equal(sim.poses()[n][0], start[n][0]) for n in start)


def test_observers_and_publications_follow_the_world(cleanup: World, arm6: World) -> None:
    """World observers see 'unloading' with the old world complete, then 'loaded'; a library user's step observer
    stays; the old world's feature observers go; a sink sees every old topic withdrawn and the new ones declared."""
    sim = Simulation(cleanup, "mujoco")
    sink = Recorder()
    sim.publications.connect(sink)
    seen: list[tuple[str, str, int]] = []
    sim.events.subscribe("world", lambda c: seen.append((c.kind, c.world.name, len(sim.entities.names))))
    steps: list[int] = []
    sim.events.subscribe("step", lambda s: steps.append(s.step_count))
    old_topics = {p.topic for p in sim.publications.declared}
    sim.step(3)
    sink.events.clear()
    sim.worlds.load(arm6)
    assert seen == [("unloading", "cleanup", len(cleanup.entities)), ("loaded", "arm6", 1)]
    withdrawn = {t for k, t in sink.events if k == "withdraw"}
    declared = {t for k, t in sink.events if k == "declare"}
    assert withdrawn == old_topics
    fresh = Simulation(arm6, "mujoco")
    fresh.publications.connect(Recorder())
    assert declared == {p.topic for p in fresh.publications.declared} == {p.topic for p in sim.publications.declared}
    assert "/referee/score" in old_topics and "/referee/score" not in declared
    steps_now = sim.events.subscriptions("step")
    assert len(steps_now) == len(fresh.events.subscriptions("step")) + 1  # the features' + ours
    sim.control.play()
    sim.step(2)
    assert steps == [1, 2, 3, 1, 2]


@pytest.mark.parametrize("backend", BACKENDS)
def test_unload_leaves_no_world(backend: str, cleanup: World) -> None:
    """After unload_world nothing steps or spawns (clear refusals), entities are none, unloading twice is refused;
    a world loaded afterwards runs."""
    sim = Simulation(cleanup, backend)
    sim.step(5)
    sim.worlds.unload()
    assert not sim.worlds.loaded and list(sim.entities.names) == [] and sim.entities == {} and sim.features == {}
    with pytest.raises(ApiError, match="no world is loaded"):
        sim.step()
    [refusal] = sim.entities.spawn([SpawnRequest(resource='<object shape="box" size="0.1 0.1 0.1" mass="1"/>')])
    assert isinstance(refusal, SpawnRefusal) and "no world is loaded" in str(refusal)
    with pytest.raises(WorldRefusal) as e:
        sim.worlds.unload()
    assert e.value.code == "NO_WORLD_LOADED"
    assert [w.name for w in sim.worlds.available()[0]][0] == "cleanup"  # the world the run started with
    sim.worlds.load(cleanup)
    sim.step(5)
    assert sim.worlds.loaded and sim.step_count == 5 and sim.worlds.elapsed_steps == 10


def test_a_world_that_cannot_be_built_is_refused_before_unloading(cleanup: World, tmp_path: Path) -> None:
    """A world whose controller or plugin does not exist is refused (located) and the running world stays."""
    for text, says in [
        ('<world><object name="a" shape="box" size="1 1 1" mass="1" controller="no.such:Thing"/></world>',
         "no.such:Thing"),
        ('<world><plugin name="no_such_feature"/></world>', "no_such_feature"),
        ('<world><plugin name="referee" rules="no_such_rules"/></world>', "rules"),
    ]:
        path = tmp_path / "w.xml"
        path.write_text(text)
        sim = Simulation(cleanup, "mujoco")
        with pytest.raises(WorldRefusal) as e:
            sim.worlds.load(parse_world(path))
        assert e.value.code == "RESOURCE_PARSE_ERROR" and says in str(e.value) and f"{path}:1:" in str(e.value)
        assert sim.worlds.loaded and sim.world is cleanup and "robot_000" in sim.entities
        sim.step(2)


class WorldSwitcher(Transport):
    """A transport (a real one, of its own kind) that loads ``world`` when the run reaches ``at`` steps and plays on."""

    name = "switcher"

    def __init__(self, world: World, at: int) -> None:
        self.world, self.at, self.sim, self.done = world, at, None, False

    def start(self, sim: Simulation) -> None:
        self.sim = sim

    def service(self, timeout: float) -> None:
        sim = self.sim
        assert sim is not None
        if not self.done and sim.worlds.elapsed_steps >= self.at:
            self.done = True
            sim.worlds.load(self.world)
            sim.control.play()

    def stop(self) -> None:
        pass


def test_run_counts_steps_across_a_world_load(cleanup: World) -> None:
    """A run of N steps in which a transport loads another world (timestep 0.004 s) takes N steps in all, and its
    report's simulated time adds both worlds' time."""
    small = open_world("", SMALL, [])
    sim = Simulation(cleanup, "mujoco")
    changes: list[WorldChange] = []
    sim.events.subscribe("world", changes.append)
    report = run(sim, steps=100, transport=WorldSwitcher(small, 40), handle_signals=False)
    assert [c.kind for c in changes] == ["unloading", "loaded"]
    assert report.steps == 100 and sim.world.name == "small" and sim.step_count == 60
    assert report.sim_time_run == pytest.approx(40 * 0.002 + 60 * 0.004, abs=1e-9)
    assert report.sim_time == pytest.approx(60 * 0.004, abs=1e-9)


@pytest.mark.slow
def test_sigcore_worlds_command(tmp_path: Path) -> None:
    """`sigcore worlds` lists the shipped worlds and a folder given; a missing path is named, exit status 2."""
    (tmp_path / "small.xml").write_text(SMALL)
    cli = [sys.executable, "-m", "sigcore"]
    r = subprocess.run([*cli, "worlds", str(tmp_path)], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "COLUMNS": "200"})
    assert r.returncode == 0, r.stderr
    assert "cleanup" in r.stdout and "arm6" in r.stdout and "small" in r.stdout and "command line" in r.stdout
    r = subprocess.run([*cli, "worlds", str(tmp_path / "gone")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and f"{tmp_path / 'gone'} (command line): no such file or folder" in r.stderr
    r = subprocess.run([*cli, "run", str(CLEANUP), "--transport", "none", "--steps", "1", "--worlds",
                        str(tmp_path / "gone")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "--worlds" in r.stderr and str(tmp_path / "gone") in r.stderr
    assert WORLDS_DIR == ROOT / "worlds"


class Exploding(Feature):
    """A feature whose constructor fails at run time (its device is missing): the world cannot be built."""

    name = "exploding_device"

    def __init__(self, sim: Simulation, config: Any) -> None:
        raise RuntimeError("no [/dev/exploding] device")


@pytest.mark.usefixtures("fresh_plugins")
def test_a_world_failing_while_being_built_leaves_no_world(cleanup: World, tmp_path: Path) -> None:
    """A world whose feature fails while it is built (after the old world was unloaded) is refused with
    OPERATION_FAILED naming the feature; no world is loaded then, and another one loads fine."""

    class Plugin:
        @staticmethod
        @sigcore.hookimpl
        def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
            register(Exploding)

    plugins.register_plugin(Plugin(), name="exploding_plugin")
    path = tmp_path / "w.xml"
    path.write_text('<world><plugin name="exploding_device"/></world>')
    sim = Simulation(cleanup, "mujoco")
    with pytest.raises(WorldRefusal) as e:
        sim.worlds.load(parse_world(path))
    assert e.value.code == "OPERATION_FAILED" and "exploding_device" in str(e.value)
    assert "no world is loaded" in str(e.value) and not sim.worlds.loaded and list(sim.entities.names) == []
    sim.worlds.load(cleanup)
    sim.control.play()
    sim.step(3)
    assert sim.worlds.loaded and "robot_000" in sim.entities and "referee" in sim.features
