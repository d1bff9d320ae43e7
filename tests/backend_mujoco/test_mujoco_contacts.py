"""Contacts as part-id pairs, mapped back to (entity, part) names."""

from __future__ import annotations


def _named(b) -> set[tuple[tuple[str, str], tuple[str, str]]]:
    return {(b.part_of(x), b.part_of(y)) for x, y in b.contacts()}


def test_contacts_cached_per_step(make_world, build) -> None:
    """contacts() is computed once per step: the same object until the next step."""
    b = build(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>'))
    b.step()
    first = b.contacts()
    assert b.contacts() is first
    b.step()
    assert b.contacts() == first
