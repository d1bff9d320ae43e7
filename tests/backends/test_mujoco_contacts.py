"""MuJoCo only: contacts computed once per step."""

from __future__ import annotations


def test_contacts_cached_per_step(make_world, build_mujoco) -> None:
    """contacts() is computed once per step: the same object until the next step."""
    b = build_mujoco(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>'))
    b.step()
    first = b.contacts()
    assert b.contacts() is first
    b.step()
    assert b.contacts() == first
