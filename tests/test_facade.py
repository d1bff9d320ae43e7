"""The Simulation is a facade over named parts (issue 29, item 2): small, with few public attributes, none of them a
mutable list or dict, and nothing outside the event hub keeps a list of observers."""

from __future__ import annotations

import ast
import inspect
import re
from collections.abc import Mapping
from pathlib import Path

import pytest

from sigcore.sim import Simulation
from sigcore.sim.features import FeatureHost
from sigcore.sim.population import Entities
from sigcore.sim.worlds import Worlds
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[1]
SIMULATION = ROOT / "sigcore" / "sim" / "simulation.py"


def public_attributes(sim: Simulation) -> dict[str, object]:
    """Public data attributes of ``sim``: instance attributes and properties (not methods)."""
    names = {n for n in vars(sim) if not n.startswith("_")}
    names |= {n for n, v in vars(Simulation).items() if not n.startswith("_") and isinstance(v, property)}
    return {n: getattr(sim, n) for n in sorted(names)}


@pytest.fixture(scope="module")
def sim() -> Simulation:
    s = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")
    s.step(5)
    return s


def test_the_facade_is_at_most_400_lines() -> None:
    lines = len(SIMULATION.read_text().splitlines())
    assert lines <= 400, f"sigcore/sim/simulation.py is {lines} lines (at most 400)"


def test_at_most_15_public_attributes_none_a_mutable_list_or_dict(sim: Simulation) -> None:
    attributes = public_attributes(sim)
    assert len(attributes) <= 15, f"{len(attributes)} public attributes: {', '.join(attributes)}"
    mutable = [n for n, v in attributes.items() if isinstance(v, list | dict | set)]
    assert mutable == [], f"public mutable containers on Simulation: {mutable}"
    assert {"entities", "features", "worlds", "control", "events"} <= set(attributes)


def test_the_parts_are_read_only(sim: Simulation) -> None:
    """No part can be replaced from outside, and what the parts hand out cannot change their state."""
    for name in public_attributes(sim):
        with pytest.raises(AttributeError):
            setattr(sim, name, None)
    assert isinstance(sim.entities, Mapping) and isinstance(sim.features, Mapping)
    with pytest.raises(TypeError):
        sim.entities["intruder"] = sim.entities["robot_000"]  # type: ignore[index]
    names = sim.entities.names
    assert isinstance(names, tuple) and isinstance(sim.entities.graspable, tuple)
    spawned = sim.entities.spawned
    spawned["ghost"] = ""  # type: ignore[index]  # a copy
    assert "ghost" not in sim.entities.spawned
    with pytest.raises(TypeError):
        sim.entities.odometry["ghost"] = None  # type: ignore[index]
    services = sim.features.services
    services["ghost"] = print  # type: ignore[index]  # a copy
    assert "ghost" not in sim.features.services


def test_the_parts_are_the_named_ones(sim: Simulation) -> None:
    assert isinstance(sim.entities, Entities) and isinstance(sim.features, FeatureHost)
    assert isinstance(sim.worlds, Worlds)
    assert list(sim.entities)[0] == "robot_000" and sim.entities["robot_000"] is sim.robot("robot_000")
    assert sorted(sim.features) == ["ik", "referee"]


def test_one_ask_for_every_feature_question(sim: Simulation) -> None:
    """summary, results, report lines and outcome are one ``ask`` each: the same answers by either route."""
    assert sim.features.summary() == sim.features.ask("summary")
    assert sim.features.results() == sim.features.ask("results")
    assert sim.features.report_lines() == [str(x) for lines in sim.features.ask("report").values() for x in lines]


OBSERVER_LIST = re.compile(r"\b\w*(observers|listeners|callbacks|subscribers)\w*\s*"
                           r"(\.append\(|\.extend\(|\+=|=\s*\[|:\s*list\[)")
VIEWER_WATCHERS = ("self.push_observers: list[", "self.snapshot_observers: list[")
"""The web viewer's own outputs (each snapshot it takes, each push its process reports), which tests and
``bench/viewer_overhead.py`` watch: not simulation events, which go through the hub."""


def test_nothing_outside_the_hub_keeps_a_list_of_observers() -> None:
    """A grep: no module of the core or the plugins appends to (or makes) a list of observers, listeners or
    subscribers, except the hub itself (``sigcore/sim/events.py``) and the controller dispatcher, whose listeners
    are the agents' own controllers (``sigcore/sim/dispatch.py``)."""
    allowed = {ROOT / "sigcore" / "sim" / "events.py", ROOT / "sigcore" / "sim" / "dispatch.py"}
    offenders = []
    for path in [*(ROOT / "sigcore").rglob("*.py"), *(ROOT / "plugins").rglob("*.py")]:
        if path in allowed or "tests" in path.parts:
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if OBSERVER_LIST.search(line) and not line.strip().startswith(VIEWER_WATCHERS):
                offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert offenders == []


def test_the_grep_finds_an_observer_list() -> None:
    assert OBSERVER_LIST.search("        self.step_observers.append(fn)")
    assert OBSERVER_LIST.search("self._listeners = []")
    assert OBSERVER_LIST.search("        self.step_observers: list[Callable[[], None]] = []")
    assert not OBSERVER_LIST.search("sim.events.subscribe('step', fn)")


def test_the_facade_delegates_what_it_does_not_own() -> None:
    """The facade's source names each part's module once in its docstring, and none of the code that moved out
    (spawn resolution, feature creation, world swapping, agent publications) is back in it."""
    tree = ast.parse(SIMULATION.read_text())
    methods = {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)}
    assert not methods & {"spawn", "add_entities", "delete", "load_world", "unload_world", "available_worlds",
                          "_create_features", "_declare_agent_publications", "summary", "results", "outcome"}
    assert inspect.getdoc(Simulation)
