"""Contacts of the last step as pairs of part ids, from ``getContactPoints``."""

from __future__ import annotations

from operator import itemgetter

import pybullet as pb

CONTACT_SLOP = 1e-3
"""A manifold point counts as a contact when its distance is below this [m]: PyBullet keeps points up to its
contact breaking threshold (2 cm) in the manifold, before and after touching; a resting contact hovers around
-0.1 mm."""

_EMPTY: frozenset[tuple[int, int]] = frozenset()
_BODIES_LINKS = itemgetter(1, 3, 2, 4)
"""``(bodyA, linkA, bodyB, linkB)`` of a ``getContactPoints`` row."""
_DISTANCE = itemgetter(8)
"""``contactDistance`` [m] of a ``getContactPoints`` row (negative: penetration)."""


class ContactMap:
    """Maps PyBullet contact points (body, link pairs) to sigcore part-id pairs.

    Args:
        part_id: Part id of every ``(body, link)``.
        entity_of_body: Entity number of every body (0: the ground).
    """

    def __init__(self, part_id: dict[tuple[int, int], int], entity_of_body: dict[int, int]) -> None:
        self._part_id = part_id
        self._entity_of_body = entity_of_body
        self._last_raw: list[tuple[int, int, int, int]] = []
        self._last_pairs = _EMPTY

    def pairs(self, client: int) -> frozenset[tuple[int, int]]:
        """Distinct ``(low, high)`` part-id pairs touching now, pairs within one entity left out.

        Resting contacts give the same manifold points, in the same order, step after step: then the previous
        answer is returned after one list comparison (about 3 us for 15 points).
        """
        points = pb.getContactPoints(physicsClientId=client)
        raw = list(map(_BODIES_LINKS, points))  # itemgetter: C speed, about 0.1 us a point
        if raw and max(map(_DISTANCE, points)) >= CONTACT_SLOP:
            raw = [key for key, p in zip(raw, points, strict=True) if p[8] < CONTACT_SLOP]
        if raw == self._last_raw:
            return self._last_pairs
        part_id, entity_of = self._part_id, self._entity_of_body
        pairs = set()
        for body_a, link_a, body_b, link_b in raw:
            if entity_of[body_a] != entity_of[body_b]:
                a, b = part_id[(body_a, link_a)], part_id[(body_b, link_b)]
                pairs.add((a, b) if a < b else (b, a))
        self._last_raw = raw
        self._last_pairs = frozenset(pairs) if pairs else _EMPTY
        return self._last_pairs
