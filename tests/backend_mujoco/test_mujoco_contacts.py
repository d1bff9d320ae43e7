"""Contacts as part-id pairs, mapped back to (entity, part) names."""

from __future__ import annotations

from mujoco_worlds import robot, run


def _named(b) -> set[tuple[tuple[str, str], tuple[str, str]]]:
    return {(b.part_of(x), b.part_of(y)) for x, y in b.contacts()}


def test_box_on_ground(make_world, build) -> None:
    """A box resting on the ground gives exactly the pair (ground, box/main), as (low id, high id)."""
    b = build(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>'))
    run(b, 0.2)
    pairs = b.contacts()
    assert all(low < high for low, high in pairs)
    assert _named(b) == {(("ground", "main"), ("box", "main"))}


def test_robot_links_touching_ground(make_world, build) -> None:
    """A robot standing on the ground touches it with its wheels and casters, by URDF link name."""
    b = build(make_world(robot()))
    run(b, 0.2)
    assert _named(b) == {(("ground", "main"), ("bot", link)) for link in ("wheel_l", "wheel_r", "caster_f",
                                                                         "caster_b")}


def test_stacked_objects_and_no_self_pairs(make_world, build) -> None:
    """A box on a box gives an object-object pair; no pair is ever within one entity."""
    b = build(make_world('<object name="a" shape="box" size="0.3 0.3 0.2" pose="0 0 0.1"/>'
                         '<object name="c" shape="box" size="0.1 0.1 0.1" pose="0 0 0.25"/>'
                         + robot("2 0 0 0 0 0")))
    run(b, 0.3)
    named = _named(b)
    assert (("a", "main"), ("c", "main")) in named
    assert all(x[0] != y[0] for x, y in named)


def test_contacts_cached_per_step(make_world, build) -> None:
    """contacts() is computed once per step: the same object until the next step."""
    b = build(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>'))
    b.step()
    first = b.contacts()
    assert b.contacts() is first
    b.step()
    assert b.contacts() == first


def test_no_contacts_in_the_air(make_world, build) -> None:
    """Nothing touching gives the empty set, and part id 0 is the ground."""
    b = build(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 3"/>'))
    b.step()
    assert b.contacts() == frozenset()
    assert b.part_of(0) == ("ground", "main")
