"""Collision bits of entities at runtime: collision mode, and grasps (see the table in :mod:`.plan`)."""

from __future__ import annotations

import mujoco
import numpy as np

from .layout import EntityIndex
from .plan import GRASPED, GRASPING, GROUP_VISUAL, HELD_PERSON, NORMAL, OFF


class CollisionBits:
    """Per-entity collision state, written to ``geom_contype``/``geom_conaffinity`` on a change.

    MuJoCo's broad phase also reads ``body_contype``/``body_conaffinity`` (the OR over a body's geoms), so
    both are kept consistent.
    """

    def __init__(self) -> None:
        self.disabled: set[str] = set()
        self.held_people: set[str] = set()
        """People held kinematically: they touch neither the ground nor one another (see :mod:`.plan`)."""
        self.grasped: dict[str, int] = {}
        self.grasping: dict[str, int] = {}

    def clear(self) -> None:
        """Back to the build state (the caller restores the model arrays)."""
        self.disabled.clear()
        self.held_people.clear()
        self.grasped.clear()
        self.grasping.clear()

    def forget(self, names: set[str]) -> None:
        """Drop the state of entities no longer in the world."""
        self.disabled -= names
        self.held_people -= names
        for table in (self.grasped, self.grasping):
            for name in names & set(table):
                del table[name]

    def apply(self, model: mujoco.MjModel, entity: EntityIndex) -> None:
        """Write the bits of ``entity``'s collision geoms from its current state."""
        name = entity.name
        if name in self.disabled:
            bits = OFF
        elif name in self.held_people:
            bits = HELD_PERSON
        elif self.grasped.get(name, 0):
            bits = GRASPED
        elif self.grasping.get(name, 0):
            bits = GRASPING
        else:
            bits = NORMAL
        geoms = entity.geoms[model.geom_group[entity.geoms] != GROUP_VISUAL]
        model.geom_contype[geoms] = bits[0]
        model.geom_conaffinity[geoms] = bits[1]
        bodies = entity.bodies
        model.body_contype[bodies] = 0
        model.body_conaffinity[bodies] = 0
        owner = model.geom_bodyid[entity.geoms]
        np.bitwise_or.at(model.body_contype, owner, model.geom_contype[entity.geoms])
        np.bitwise_or.at(model.body_conaffinity, owner, model.geom_conaffinity[entity.geoms])

    def hold_person(self, model: mujoco.MjModel, entity: EntityIndex, held: bool) -> None:
        """A person held (or freed): its bits follow (:attr:`held_people`)."""
        if entity.kind != "human" or held == (entity.name in self.held_people):
            return
        if held:
            self.held_people.add(entity.name)
        else:
            self.held_people.discard(entity.name)
        self.apply(model, entity)

    @staticmethod
    def count(table: dict[str, int], name: str, delta: int) -> None:
        """Add ``delta`` to ``table[name]``, dropping it at zero."""
        value = table.get(name, 0) + delta
        if value > 0:
            table[name] = value
        else:
            table.pop(name, None)
