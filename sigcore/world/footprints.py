"""Boxes around entities and the tops they rest on, for placing entities without overlap
(:mod:`sigcore.world.randomize`).

An entity's box is :func:`local_bounds` (its visuals, in its own frame); turned by its
orientation it becomes an axis-aligned box of offsets from its position, whose x-y part is its footprint. The boxes
are rounded to 6 decimals and the placement arithmetic uses only :mod:`math`, so that the same numbers come out on
every machine.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from .appearance import entity_scene, links_in_root, visual_corners
from .models import Entity, Human, Robot, World

log = logging.getLogger("sigcore.randomize")

Box = tuple[float, float, float, float, float, float]
"""An axis-aligned box ``(x0, y0, z0, x1, y1, z1)`` [m]."""

Rect = tuple[float, float, float, float]
"""An axis-aligned rectangle ``(x0, y0, x1, y1)`` [m]."""

LEVEL = 1e-6
"""Largest roll or pitch of a surface entity [rad]: beyond it its top is not level."""


Bounds = tuple[tuple[float, float, float], tuple[float, float, float]]
"""``(min xyz, max xyz)`` of a box [m]."""


def local_bounds(entity: Entity, world: World) -> Bounds | None:
    """The axis-aligned box around ``entity``'s visuals in its own frame (its pose ignored, joints at zero) [m];
    None when a mesh's vertices cannot be read."""
    scene = entity_scene(world, entity, lambda _robot, link: link)
    frames: dict[str, tuple[np.ndarray, np.ndarray]] = {entity.name: (np.zeros(3), np.array([1.0, 0, 0, 0]))}
    if isinstance(entity, Robot | Human):
        document = world.urdf(entity.name)
        frames.update(links_in_root(document.root, document.model.root))
    points = []
    for visual in scene.visuals:
        corners = visual_corners(visual, *frames[visual.frame])
        if corners is None:
            return None
        points.append(corners)
    if not points:
        return None
    every = np.vstack(points)
    lo_, hi_ = (tuple(round(float(v), 6) + 0.0 for v in every.min(axis=0)),  # + 0.0: no -0.0
                tuple(round(float(v), 6) + 0.0 for v in every.max(axis=0)))
    return (lo_[0], lo_[1], lo_[2]), (hi_[0], hi_[1], hi_[2])


def bounds_of(entity: Entity, world: World) -> Bounds | None:
    """:func:`local_bounds` of ``entity``; None when they are unknown (a mesh that
    cannot be read)."""
    try:
        return local_bounds(entity, world)
    except (OSError, ValueError, KeyError) as e:
        log.debug("bounds of '%s' unknown: %s", entity.name, e)
        return None


def turned(bounds: Bounds, rpy: tuple[float, float, float]) -> Box:
    """The axis-aligned box around ``bounds`` (a box in an entity's frame) turned by roll, pitch, yaw (fixed axes x,
    y, z), as offsets from the entity's position [m]."""
    m = _matrix(*rpy)
    lo, hi = bounds
    corners = [(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    axes = [[row[0] * x + row[1] * y + row[2] * z for x, y, z in corners] for row in m]
    return min(axes[0]), min(axes[1]), min(axes[2]), max(axes[0]), max(axes[1]), max(axes[2])


def placed_box(bounds: Bounds, xyz: tuple[float, float, float], rpy: tuple[float, float, float]) -> Box:
    """The box in world around an entity of ``bounds`` at position ``xyz`` [m] and orientation ``rpy`` [rad]."""
    box = turned(bounds, rpy)
    x, y, z = xyz
    return box[0] + x, box[1] + y, box[2] + z, box[3] + x, box[4] + y, box[5] + z


def grown(box: Box, margin: float) -> Box:
    """``box`` grown by ``margin`` [m] on every side seen from above (its height range kept)."""
    return box[0] - margin, box[1] - margin, box[2], box[3] + margin, box[4] + margin, box[5]


def overlap_xy(a: Box, b: Box) -> bool:
    """Whether two boxes overlap seen from above (touching is not overlapping)."""
    return a[0] < b[3] and b[0] < a[3] and a[1] < b[4] and b[1] < a[4]


def overlap_z(a: Box, b: Box) -> bool:
    """Whether the height ranges of two boxes overlap (touching is not overlapping)."""
    return a[2] < b[5] and b[2] < a[5]


def _matrix(roll: float, pitch: float, yaw: float) -> tuple[tuple[float, float, float], ...]:
    """Rz(yaw) Ry(pitch) Rx(roll), by rows."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return ((cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
            (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
            (-sp, cp * sr, cp * cr))


@dataclass(frozen=True)
class Surface:
    """The level top face of an entity: a rectangle in the entity's frame, at a height in world.

    Attributes:
        name: The entity.
        x: Its position's x in world [m].
        y: Its position's y in world [m].
        yaw: Its yaw [rad] (its roll and pitch are 0).
        rect: The top face in the entity's frame [m].
        top: Height of the top face in world [m].
    """

    name: str
    x: float
    y: float
    yaw: float
    rect: Rect
    top: float

    @property
    def axis_aligned(self) -> bool:
        """Whether its frame's axes are the world's (a yaw of a multiple of 90°, to 1e-12)."""
        return abs(math.sin(2 * self.yaw)) < 1e-12

    def world_box(self, rect: Rect) -> Rect:
        """The rectangle in world around ``rect`` (a rectangle in the entity's frame)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        corners = [(u, v) for u in (rect[0], rect[2]) for v in (rect[1], rect[3])]
        xs = [self.x + c * u - s * v for u, v in corners]
        ys = [self.y + s * u + c * v for u, v in corners]
        return min(xs), min(ys), max(xs), max(ys)

    def local(self, x: float, y: float) -> tuple[float, float]:
        """The point ``(x, y)`` of world [m] in the entity's frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return c * (x - self.x) + s * (y - self.y), -s * (x - self.x) + c * (y - self.y)

    def room(self, bounds: Bounds, rpy: tuple[float, float, float], clearance: float) -> tuple[Rect, float] | None:
        """Where the position of an entity of ``bounds`` turned by ``rpy`` (in world) may be for its footprint to
        stay ``clearance`` [m] inside the top's edges: a rectangle in this entity's frame, and the height in world
        at which it rests on the top (its bottom on it); None when it is too large."""
        u0, v0, z0, u1, v1, _ = turned(bounds, (rpy[0], rpy[1], rpy[2] - self.yaw))
        rect = (self.rect[0] - u0 + clearance, self.rect[1] - v0 + clearance,
                self.rect[2] - u1 - clearance, self.rect[3] - v1 - clearance)
        if rect[0] > rect[2] or rect[1] > rect[3]:
            return None
        return rect, self.top - z0


def surface_of(entity: Entity, world: World) -> Surface | None:
    """The top face of ``entity`` (the top of its box); None when its bounds are unknown or it is tilted (a roll
    or pitch beyond 1e-6 rad)."""
    bounds = bounds_of(entity, world)
    roll, pitch, yaw = entity.pose.rpy
    if bounds is None or abs(roll) > LEVEL or abs(pitch) > LEVEL:
        return None
    (u0, v0, _), (u1, v1, z1) = bounds
    x, y, z = entity.pose.xyz
    return Surface(entity.name, x, y, yaw, (u0, v0, u1, v1), z + z1)
