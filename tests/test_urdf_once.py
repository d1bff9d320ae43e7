"""Each URDF file of a world is read and parsed once, and the parsed document is shared (``World.urdf``)."""

from __future__ import annotations

import os
import sys
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pinocchio as pin
import pytest
from lxml import etree

from sigcore.sim import Simulation
from sigcore.world import Object, UrdfError, World, parse_world

WORLDS = Path(__file__).parent.parent / "worlds"
CLEANUP = WORLDS / "cleanup.xml"
SIGBOT = WORLDS / "models" / "sigbot" / "sigbot.urdf"
TRASHBOX = WORLDS / "models" / "trashbox" / "trashbox.urdf"


class UrdfReads:
    """Counts, per URDF file, the reads of the file and the parses of its content.

    A read is a Python ``open`` of the file (seen through the ``open`` audit event) or a library given the file's
    path (``lxml.etree.parse``, ``pinocchio.buildModelFromUrdf``). A parse is lxml turning the file into a tree
    (given its path, or its whole content as bytes or text). An engine import is Pinocchio building its model
    from the file's text (it takes no lxml tree); the physics engines import rewritten copies, not counted.
    """

    def __init__(self, files: list[Path]) -> None:
        self.content = {f.resolve(): f.read_bytes() for f in files}
        self.reads: Counter[Path] = Counter()
        self.parses: Counter[Path] = Counter()
        self.engine: Counter[Path] = Counter()

    def file(self, source: Any) -> Path | None:
        """The counted file that ``source`` (a path as str, bytes or PathLike) names, if any."""
        if isinstance(source, bytes):
            source = os.fsdecode(source)
        if not isinstance(source, str | os.PathLike):
            return None
        path = Path(source).resolve()
        return path if path in self.content else None

    def of_content(self, data: Any) -> Path | None:
        """The counted file whose whole content is ``data`` (bytes or text), if any."""
        raw = data.encode("utf-8") if isinstance(data, str) else data
        return next((f for f, c in self.content.items() if c == raw), None)

    def on_path(self, source: Any) -> None:
        path = self.file(source)
        if path is not None:
            self.reads[path] += 1
            self.parses[path] += 1

    def on_text(self, data: Any) -> None:
        path = self.of_content(data)
        if path is not None:
            self.parses[path] += 1

    def on_engine_text(self, data: Any) -> None:
        path = self.of_content(data)
        if path is not None:
            self.engine[path] += 1

    def on_open(self, source: Any) -> None:
        path = self.file(source)
        if path is not None:
            self.reads[path] += 1


_ACTIVE: list[UrdfReads] = []


def _audit(event: str, args: tuple[Any, ...]) -> None:
    if event == "open" and _ACTIVE:
        _ACTIVE[-1].on_open(args[0])


sys.addaudithook(_audit)  # audit hooks cannot be removed; it counts only while a test has a UrdfReads active


@pytest.fixture
def count_urdf(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    """``count_urdf(files)``: start counting reads and parses of ``files`` until the test ends."""

    def wrap(owner: Any, name: str, on: Any) -> None:
        original = getattr(owner, name)

        def counted(source: Any, *args: Any, **kwargs: Any) -> Any:
            if _ACTIVE:
                on(_ACTIVE[-1])(source)
            return original(source, *args, **kwargs)

        monkeypatch.setattr(owner, name, counted)

    def start(files: list[Path]) -> UrdfReads:
        reads = UrdfReads(files)
        wrap(etree, "parse", lambda r: r.on_path)
        wrap(etree, "fromstring", lambda r: r.on_text)
        wrap(etree, "XML", lambda r: r.on_text)
        wrap(pin, "buildModelFromUrdf", lambda r: r.on_path)
        wrap(pin, "buildModelFromXML", lambda r: r.on_engine_text)
        _ACTIVE.append(reads)
        return reads

    yield start
    _ACTIVE.clear()


def _world_urdfs(world_file: Path) -> list[Path]:
    root = etree.fromstring(world_file.read_bytes())
    return sorted({(world_file.parent / str(e.get("urdf"))).resolve() for e in root if e.get("urdf")})


@pytest.mark.parametrize("backend", ["mujoco", "bullet"])
def test_cleanup_world_reads_and_parses_each_urdf_once(backend: str, count_urdf: Any) -> None:
    """Parsing and building the clean-up world (referee and IK on) reads and parses each URDF file exactly once
    (before the shared document: sigbot 5, table 4, wagon 2, trashbox 9 times each)."""
    files = _world_urdfs(CLEANUP)
    assert [f.name for f in files] == ["sigbot.urdf", "table.urdf", "trashbox.urdf", "wagon.urdf"]
    reads = count_urdf(files)
    sim = Simulation(parse_world(CLEANUP), backend)
    assert {"referee", "ik"} <= set(sim.features)
    assert dict(reads.reads) == {f: 1 for f in files}, "file reads per URDF"
    assert dict(reads.parses) == {f: 1 for f in files}, "lxml parses per URDF"
    assert dict(reads.engine) == {SIGBOT.resolve(): 1}, "IK builds its model once, from the shared text"


def test_world_built_without_parser_loads_a_urdf_on_first_use(count_urdf: Any) -> None:
    """A World made directly from models reads a URDF on first use only, and every entity using it shares it."""
    world = World(agents=(Object(name="tb_0", urdf=TRASHBOX, static=True),
                          Object(name="tb_1", urdf=TRASHBOX, static=True)), source=WORLDS / "direct.xml")
    reads = count_urdf([TRASHBOX])
    assert reads.reads[TRASHBOX.resolve()] == 0
    first = world.urdf("tb_0")
    assert world.urdf("tb_1") is first and world.urdf(TRASHBOX) is first
    assert first.model.links == ("trashbox_link",)
    assert reads.reads[TRASHBOX.resolve()] == 1 and reads.parses[TRASHBOX.resolve()] == 1


def test_world_urdf_names_the_agents_that_have_one() -> None:
    """Asking for the URDF of an agent without one (or of no agent) names the agents that have a URDF."""
    world = parse_world(CLEANUP)
    known = "robot_000, table_0, table_1, wagon, trashbox_0, trashbox_1, trashbox_2, man_0"
    with pytest.raises(KeyError) as no_urdf:
        world.urdf("wall_north")
    assert no_urdf.value.args[0] == f"agent 'wall_north' has no URDF; agents with one: {known}"
    person = world.urdf("man_0")  # a person's URDF is generated, once per height and mass
    assert person.model.root == "main" and "l_knee" in person.model.links and world.urdf("man_0") is person
    with pytest.raises(KeyError) as no_agent:
        world.urdf("nobody")
    assert no_agent.value.args[0] == f"no agent 'nobody'; agents with a URDF: {known}"


def test_world_urdf_of_a_missing_file_is_a_urdf_error(tmp_path: Path) -> None:
    """A URDF path that cannot be read raises UrdfError naming the file."""
    world = World(source=tmp_path / "w.xml")
    with pytest.raises(UrdfError, match=r"missing\.urdf:0: cannot read"):
        world.urdf(Path("missing.urdf"))


@pytest.mark.parametrize("backend", ["mujoco", "bullet"])
def test_backends_leave_the_shared_document_unchanged(backend: str) -> None:
    """Building a world does not change the shared parsed URDF (backends strip visuals from their own copy)."""
    world = parse_world(CLEANUP)
    document = world.urdf("robot_000")
    before = etree.tostring(document.root)
    assert document.root.find("link/visual") is not None
    Simulation(world, backend)
    assert etree.tostring(document.root) == before


def test_entities_and_the_simulation_share_one_document_per_file() -> None:
    """Entities using the same file get the same document, and ``Simulation.urdf`` is that document's names."""
    world = parse_world(CLEANUP)
    assert world.urdf("trashbox_0") is world.urdf("trashbox_2") is world.urdf(Path("models/trashbox/trashbox.urdf"))
    sim = Simulation(world, "mujoco")
    assert sim.entities.urdf("robot_000") is world.urdf("robot_000").model
    assert sim.entities.urdf("robot_000").root == "base_link"
