"""MuJoCo only: contacts computed once per step, and read through a view of MuJoCo's contact array."""

from __future__ import annotations

import numpy as np
from sigcore_backend_mujoco.contacts import ContactMap


def test_contacts_cached_per_step(make_world, build_mujoco) -> None:
    """contacts() is computed once per step: the same object until the next step."""
    b = build_mujoco(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>'))
    b.step()
    first = b.contacts()
    assert b.contacts() is first
    b.step()
    assert b.contacts() == first


def test_contact_pairs_read_through_the_view_match_a_fresh_reading_every_step(make_world, build_mujoco) -> None:
    """The contact map compares the step's contacts through a view of MuJoCo's contact array made once: at every
    step of a run where contacts come and go (boxes falling on each other, a ball rolling off), across a reset and
    a spawn (a new model and data), its pairs equal those of a new map reading ``data.contact`` afresh, and its view
    holds the geom ids ``data.contact`` has."""
    b = build_mujoco(make_world(
        '<object name="a" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>\n'
        '<object name="b" shape="box" size="0.1 0.1 0.1" pose="0.02 0 0.5"/>\n'
        '<object name="ball" shape="sphere" size="0.05" pose="0.05 0.01 0.9"/>'))
    seen: set[frozenset[tuple[int, int]]] = set()

    def check(steps: int) -> None:
        for _ in range(steps):
            b.step()
            pairs = b.contacts()
            fresh = ContactMap(b._layout.geom_part, b._layout.part_entity).pairs(b.data)  # type: ignore[attr-defined]
            assert pairs == fresh
            view = b._contact_map._view  # type: ignore[attr-defined]
            ncon = b.data.ncon  # type: ignore[attr-defined]
            if ncon:
                assert np.array_equal(view[:ncon], b.data.contact.geom)  # type: ignore[attr-defined]
            seen.add(pairs)

    check(600)
    assert len(seen) >= 3, f"the contacts hardly changed: {seen}"
    b.reset()
    check(50)
    world = make_world('<object name="a" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>\n'
                       '<object name="b" shape="box" size="0.1 0.1 0.1" pose="0.02 0 0.5"/>\n'
                       '<object name="ball" shape="sphere" size="0.05" pose="0.05 0.01 0.9"/>\n'
                       '<object name="c" shape="box" size="0.1 0.1 0.1" pose="1 0 0.3"/>', name="w2")
    b.add_entities(world, ["c"])
    check(300)
