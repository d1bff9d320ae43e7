"""Clean-up rule for trash items: first grasp, and where each released item comes to rest."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from sigcore.sim.simulation import Simulation

from .boxes import Array, TrashBox
from .config import RefereeConfig
from .events import Kind

Award = Callable[[Kind, str, int], None]
"""``award(kind, text, points)``: record an event (the feature's scorer)."""

MOVE_TOLERANCE = 0.02
"""An item further than this from where it last came to rest has been moved and is judged again [m]."""


@dataclass
class ItemState:
    """What the referee knows about one trash item.

    Attributes:
        name: The item's entity name.
        kinds: Its tags other than the trash tag (matched against the boxes' tags).
        rest_position: Centre of mass where it was last judged (or its start) [m].
        grasped: It has been grasped at least once (the grasp bonus is given once).
        held: It was held at the last look.
        pending: Released or moved since it was last judged: judge it when it comes to rest.
        rest_since: Simulation time since which it has been slower than ``rest_speed`` [s], or None.
        box: The trash box it was scored in (final), or None.
        correct: Whether that box accepted it (kept when the box is deleted later), or None.
        fresh: Spawned while running and not yet at rest: its first rest is judged only inside a box (one
            dropped onto the floor or a table is not 'outside', it is where it starts).
    """

    name: str
    kinds: frozenset[str]
    rest_position: Array
    grasped: bool = False
    held: bool = False
    pending: bool = False
    rest_since: float | None = None
    box: str | None = field(default=None)
    correct: bool | None = None
    fresh: bool = False


class ItemRule:
    """Watches the trash items at the referee's rate and awards grasps and boxes."""

    def __init__(self, sim: Simulation, config: RefereeConfig, items: dict[str, frozenset[str]],
                 boxes: list[TrashBox], award: Award) -> None:
        self.sim, self.config, self.boxes, self.award = sim, config, boxes, award
        self.items = {name: ItemState(name, kinds, sim.backend.get_com(name)) for name, kinds in items.items()}

    def reset(self) -> None:
        """Forget every item's history (a new trial from the current state)."""
        for state in self.items.values():
            self.items[state.name] = ItemState(state.name, state.kinds, self.sim.backend.get_com(state.name))

    def add_item(self, name: str, kinds: frozenset[str]) -> None:
        """Watch trash item ``name``, spawned while running, from where it first comes to rest."""
        self.items[name] = ItemState(name, kinds, self.sim.backend.get_com(name), fresh=True)

    def add_box(self, box: TrashBox) -> None:
        """Judge items against trash box ``box`` too (spawned while running)."""
        self.boxes.append(box)

    def remove(self, name: str) -> None:
        """Forget item or box ``name`` (deleted); the events it earned stay, and items scored in a deleted box
        stay scored."""
        self.items.pop(name, None)
        self.boxes = [b for b in self.boxes if b.name != name]

    @property
    def done(self) -> bool:
        """There are items and every one has been scored in a box."""
        return bool(self.items) and all(s.box is not None for s in self.items.values())

    def correct(self, item: str, box: TrashBox) -> bool:
        """Whether ``box`` accepts ``item`` (they share a tag)."""
        return bool(self.items[item].kinds & box.accepts)

    def look(self, now: float) -> None:
        """One look at every item not yet scored."""
        for state in self.items.values():
            if state.box is None:
                self._look(state, now)

    def _look(self, state: ItemState, now: float) -> None:
        holder = self.sim.entities.grasps.held_by(state.name)
        if holder is not None:
            if not state.grasped:
                state.grasped = True
                self.award("grasp", f"{holder[0]} grasped {state.name}", self.config.grasp)
            state.held, state.pending, state.rest_since, state.fresh = True, True, None, False
            return
        state.held = False
        speed = math.hypot(*self.sim.backend.get_velocity(state.name)[0])  # np.linalg.norm: 2.5 µs
        if speed > self.config.rest_speed:
            state.rest_since = None
            return
        if state.rest_since is None:
            state.rest_since = now
        com = self.sim.backend.get_com(state.name)
        moved = math.dist(com, state.rest_position) > MOVE_TOLERANCE
        if (state.pending or moved or state.fresh) and now - state.rest_since >= self.config.rest_time - 1e-9:
            state.pending, state.rest_position = False, com
            self._judge(state, com)
            state.fresh = False

    def _judge(self, state: ItemState, com: Array) -> None:
        for box in self.boxes:
            position, quaternion = self.sim.backend.get_pose(box.name)
            if box.contains(com, position, quaternion):
                state.box, state.correct = box.name, self.correct(state.name, box)
                if state.correct:
                    self.award("correct_box", f"{state.name} in {box.name}", self.config.correct_box)
                else:
                    self.award("wrong_box", f"{state.name} in {box.name}, which takes "
                               f"{' '.join(sorted(box.accepts))}", self.config.wrong_box)
                return
        if state.fresh:
            return
        x, y, z = com
        self.award("outside", f"{state.name} came to rest outside every trash box at ({x:.2f}, {y:.2f}, "
                   f"{z:.2f})", 0)
