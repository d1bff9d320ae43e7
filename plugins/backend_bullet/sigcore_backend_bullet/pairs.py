"""Collision-filter pair entries (``setCollisionFilterPair``), kept equal to the group/mask rule except during grasps.

A grasp keeps the held object from colliding with the robot holding it through a pair entry per link pair, which
leaves the broadphase as it is (see :mod:`.grasp`). PyBullet 3.2.7 cannot delete such an entry: setting it to 1
does not bring back the group/mask rule but overrides it (an object whose collision is later switched off would
still collide with that robot), and ``removeBody`` leaves the entries behind for the next body that gets the freed
id (PyBullet reuses ids). Only ``resetSimulation`` clears them. So :class:`PairFilters` remembers every entry set in
the client and keeps each one equal to what the groups and masks of its two links say (the table in
:mod:`.layout`), except for the pairs that a grasp holds apart.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable

import pybullet as pb

from .layout import EntityIndex

Bits = Callable[[EntityIndex, int], tuple[int, int]]
"""``(group, mask)`` of one link of an entity as it is now."""


def collides(a: tuple[int, int], b: tuple[int, int]) -> bool:
    """Whether two links with these ``(group, mask)`` collide: PyBullet 3.2.7's ``g1 & m2 or g2 & m1``."""
    return bool(a[0] & b[1] or b[0] & a[1])


class PairFilters:
    """Every pair entry set in one client (forget them all with :meth:`clear` after ``resetSimulation``)."""

    def __init__(self) -> None:
        self._value: dict[tuple[int, int, int, int], bool] = {}
        """``(body a, link a, body b, link b)`` with ``body a < body b`` -> the value set."""
        self._apart: Counter[tuple[int, int]] = Counter()
        """Body pairs ``(low, high)`` held apart, with the number of grasps holding them."""

    def clear(self) -> None:
        """Forget every entry (the client was reset)."""
        self._value.clear()
        self._apart.clear()

    def hold_apart(self, client: int, a: EntityIndex, b: EntityIndex) -> None:
        """No link of ``a`` collides with a link of ``b`` until as many :meth:`release` calls."""
        self._apart[_bodies(a.body, b.body)] += 1
        for la in a.links:
            for lb in b.links:
                self._set(client, a.body, la, b.body, lb, False)

    def release(self, client: int, a: EntityIndex, b: EntityIndex, bits: Bits) -> None:
        """Undo one :meth:`hold_apart`; once none is left, ``a`` and ``b`` collide as their groups and masks say."""
        key = _bodies(a.body, b.body)
        self._apart[key] -= 1
        if self._apart[key] > 0:
            return
        del self._apart[key]
        for la in a.links:
            for lb in b.links:
                self._set(client, a.body, la, b.body, lb, collides(bits(a, la), bits(b, lb)))

    def sync(self, client: int, entities: dict[int, EntityIndex], bits: Bits) -> None:
        """Set every remembered entry between links of ``entities`` (by body id) to the group/mask rule, or to
        "apart" for a grasp; entries of bodies that no longer exist wait for a body that reuses the id."""
        if not self._value:
            return
        for (body_a, link_a, body_b, link_b), value in list(self._value.items()):
            a, b = entities.get(body_a), entities.get(body_b)
            if a is None or b is None or link_a not in a.links or link_b not in b.links:
                continue
            wanted = (body_a, body_b) not in self._apart and collides(bits(a, link_a), bits(b, link_b))
            if wanted != value:
                self._set(client, body_a, link_a, body_b, link_b, wanted)

    def _set(self, client: int, body_a: int, link_a: int, body_b: int, link_b: int, enabled: bool) -> None:
        if body_a > body_b:
            body_a, link_a, body_b, link_b = body_b, link_b, body_a, link_a
        pb.setCollisionFilterPair(body_a, body_b, link_a, link_b, int(enabled), physicsClientId=client)
        self._value[(body_a, link_a, body_b, link_b)] = enabled


def _bodies(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)
