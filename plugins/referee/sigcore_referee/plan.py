"""The clean-up plan of the scripted robot: which arm picks each trash item from where, and which box it goes to.

Assumes the clean-up world's layout (worlds/cleanup.xml): items on furniture on one side of a free corridor along
x, trash boxes on either side; the robot approaches each across the corridor (facing +y or -y).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sigcore.sim.simulation import Simulation

PICK_AHEAD = 0.50
"""Item this far ahead of base_link when picking [m] (base front 0.10 m from a table edge 0.15 m away)."""
PICK_SIDE = 0.20
"""... and this far to the side of the arm in use (under its shoulder) [m]."""
DROP_AHEAD = 0.52
"""Box opening centre this far ahead of base_link when dropping [m] (base front 0.05 m from the box)."""
DROP_SIDE = 0.10
"""... and this far to the side of the arm in use [m]."""
STAGE = 0.80
"""Back off this far from a pick or drop pose, along the approach, before driving elsewhere [m]."""


@dataclass(frozen=True)
class Stop:
    """A base pose to pick or drop from.

    Attributes:
        x: Base position x [m].
        y: Base position y [m].
        yaw: Heading [rad] (±π/2: across the corridor).
        stage_x: Where to come from and back off to, x [m].
        stage_y: ... y [m].
    """

    x: float
    y: float
    yaw: float
    stage_x: float
    stage_y: float


@dataclass(frozen=True)
class Job:
    """One trash item to clean up.

    Attributes:
        item: The item.
        box: The box that accepts it.
        side: ``"l"`` or ``"r"``: the arm.
        pick: Where to pick it from.
        drop: Where to drop it from.
    """

    item: str
    box: str
    side: str
    pick: Stop
    drop: Stop


def _stop(tx: float, ty: float, ahead: float, side_offset: float, side: str) -> Stop:
    yaw = math.pi / 2 if ty > 0 else -math.pi / 2
    fx, fy = math.cos(yaw), math.sin(yaw)
    lx, ly = -fy, fx
    s = side_offset if side == "l" else -side_offset
    x, y = tx - ahead * fx - s * lx, ty - ahead * fy - s * ly
    return Stop(float(x), float(y), yaw, float(x - STAGE * fx), float(y - STAGE * fy))


def plan(sim: Simulation, trash_tag: str = "trash", box_tag: str = "trashbox",
         furniture_tag: str = "furniture") -> list[Job]:
    """A job per trash item, in world order; the arm is the one that puts the base nearer the centre of the
    furniture the item is on (both are within reach).

    Raises:
        ValueError: an item that no box accepts.
    """
    entities = sim.world.entities
    boxes = [(e.name, set(e.tags) - {box_tag}) for e in entities if box_tag in e.tags]
    furniture = [e.name for e in entities if furniture_tag in e.tags]
    jobs = []
    for item in (e for e in entities if trash_tag in e.tags):
        kinds = set(item.tags) - {trash_tag}
        box = next((name for name, accepts in boxes if accepts & kinds), None)
        if box is None:
            raise ValueError(f"no box tagged '{box_tag}' accepts '{item.name}' ({' '.join(sorted(kinds))})")
        ix, iy = (float(v) for v in sim.backend.get_com(item.name)[:2])
        bx, by = (float(v) for v in sim.backend.get_pose(box)[0][:2])
        side = "l"
        if furniture:
            support = min(furniture, key=lambda f: math.dist(sim.backend.get_pose(f)[0][:2], (ix, iy)))
            cx = sim.backend.get_pose(support)[0][:2]
            side = min("lr", key=lambda s: math.dist((_stop(ix, iy, PICK_AHEAD, PICK_SIDE, s).x,
                                                      _stop(ix, iy, PICK_AHEAD, PICK_SIDE, s).y), cx))
        jobs.append(Job(item.name, box, side, _stop(ix, iy, PICK_AHEAD, PICK_SIDE, side),
                        _stop(bx, by, DROP_AHEAD, DROP_SIDE, side)))
    return jobs
