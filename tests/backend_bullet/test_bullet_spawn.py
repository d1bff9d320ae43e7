"""PyBullet-specific behaviour of adding and removing entities while running (the shared behaviour is in
tests/backends/test_conformance_spawn.py): refusals, reused body ids, the rebuild on reset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pybullet as pb
import pytest
from sigcore_backend_bullet import BulletBackend

from sigcore.errors import BackendRefusal
from sigcore.world import World, parse_world

WORLD = """<world name="w">
  <object name="a" shape="box" size="0.1 0.1 0.1" pose="0 0 0.05"/>
  <object name="b" shape="sphere" size="0.05" pose="1 0 0.05"/>
  <object name="c" shape="box" size="0.2 0.2 0.2" pose="2 0 0.1"/>
  <agent name="mod"/>
</world>"""


def _worlds(tmp_path: Path) -> tuple[World, World]:
    """The full world and the same without ``b`` and ``c``."""
    full = parse_world(tmp_path / "w.xml", WORLD)
    return full, full.with_agents(tuple(a for a in full.agents if a.name not in {"b", "c"}))


def test_refusals_name_what_was_wrong_and_add_nothing(tmp_path: Path) -> None:
    """Adding a name already in the world, the same name twice, a name not in the world or a bodiless agent is
    refused naming it, and no body is created."""
    full, start = _worlds(tmp_path)
    backend = BulletBackend()
    backend.build(start)
    bodies = pb.getNumBodies(physicsClientId=backend.client)
    for names, message in ((["a"], "'a' is already in the world"), (["b", "b"], "'b' is already in the world"),
                           (["zz"], "no agent 'zz'.*agents: a, b, c, mod"), (["mod"], "'mod' has no body")):
        with pytest.raises(BackendRefusal, match=message):
            backend.add_entities(full, names)
        assert pb.getNumBodies(physicsClientId=backend.client) == bodies
    with pytest.raises(BackendRefusal, match="no entity 'b'"):
        backend.parts("b")


def test_reused_body_id_is_a_new_entity(tmp_path: Path) -> None:
    """PyBullet gives an added body the id of a removed one: contacts and poses name the new entity, not the old."""
    full, start = _worlds(tmp_path)
    backend = BulletBackend()
    backend.build(full)
    body_b = backend._entities["b"].body
    backend.remove_entities(full.with_agents(tuple(a for a in full.agents if a.name != "c")), ["c"])
    backend.remove_entities(start, ["b"])  # PyBullet hands out the id freed last first
    backend.add_entities(full.with_agents(tuple(a for a in full.agents if a.name != "b")), ["c"])
    assert backend._entities["c"].body == body_b  # what this test is about: the id was reused
    for _ in range(50):
        backend.step()
    touching = {frozenset((backend.part_of(i)[0], backend.part_of(j)[0])) for i, j in backend.contacts()}
    assert touching == {frozenset(("a", "ground")), frozenset(("c", "ground"))}
    assert backend.get_pose("c")[0] == pytest.approx(np.array([2.0, 0.0, 0.1]), abs=3e-3)
