"""Trash boxes: the inner volume of a box (from its URDF, shared by the world, or given) and the point-in-box
test."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from sigcore.geometry import quat_conj, quat_rotate
from sigcore.world.exceptions import UrdfError
from sigcore.world.limits import parse_floats
from sigcore.world.urdf import UrdfDocument

from .exceptions import BoxGeometryError

Array = npt.NDArray[np.float64]
Bounds = tuple[float, float, float, float, float, float]
"""``(x0, y0, z0, x1, y1, z1)``: an axis-aligned volume in a box's frame [m]."""

_FLAT = 1e-9


@dataclass(frozen=True)
class TrashBox:
    """A trash box: which items it accepts and the volume an item must rest in.

    Attributes:
        name: The box's entity name.
        accepts: Its tags other than the box tag (an item is right for it if they share one).
        inner: The inner volume in the box's frame [m].
    """

    name: str
    accepts: frozenset[str]
    inner: Bounds

    def contains(self, point: Array, box_position: Array, box_quaternion: Array) -> bool:
        """Whether world point ``point`` [m] is inside the inner volume, the box being at that pose."""
        local = quat_rotate(quat_conj(box_quaternion), np.asarray(point, dtype=float) - box_position)
        x0, y0, z0, x1, y1, z1 = self.inner
        return bool(x0 <= local[0] <= x1 and y0 <= local[1] <= y1 and z0 <= local[2] <= z1)


def _numbers(text: str | None, n: int, default: str) -> tuple[float, ...]:
    return parse_floats(text or default, n)


def _collision_boxes(box: str, document: UrdfDocument, scale: float) -> list[Bounds]:
    root, urdf = document.root, document.path  # the shared tree: only read here
    links = root.findall("link")
    if len(links) != 1:
        raise BoxGeometryError(box, f"{urdf} has {len(links)} links; only one-link boxes are read")
    boxes: list[Bounds] = []
    for col in links[0].findall("collision"):
        geometry = col.find("geometry")
        shape = geometry.find("box") if geometry is not None else None
        if shape is None:
            raise BoxGeometryError(box, f"{urdf}:{col.sourceline}: only <box> collision geometry is read")
        origin = col.find("origin")
        try:
            xyz = _numbers(origin.get("xyz") if origin is not None else None, 3, "0 0 0")
            rpy = _numbers(origin.get("rpy") if origin is not None else None, 3, "0 0 0")
            size = _numbers(shape.get("size"), 3, "")
        except ValueError as e:
            raise BoxGeometryError(box, f"{urdf}:{col.sourceline}: {e}") from None
        if any(abs(a) > _FLAT for a in rpy):
            raise BoxGeometryError(box, f"{urdf}:{col.sourceline}: a rotated collision box")
        lo = [scale * (c - s / 2) for c, s in zip(xyz, size, strict=True)]
        hi = [scale * (c + s / 2) for c, s in zip(xyz, size, strict=True)]
        boxes.append((lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]))
    if not boxes:
        raise BoxGeometryError(box, f"{urdf} has no collision geometry")
    return boxes


def inner_volume(box: str, urdf: UrdfDocument | Path, scale: float = 1.0) -> Bounds:
    """The empty volume of an open-top box model made of axis-aligned collision boxes (a floor and walls).

    Seen from the centre of the model's footprint: the floor is the part under the centre, the walls are the
    nearest parts on each side; the volume goes from the floor's top to the highest wall top (the rim).

    Args:
        box: The box's entity name, for messages.
        urdf: Its parsed URDF (``World.urdf``, not read again), or a URDF file to read.
        scale: The object's scale factor.

    Raises:
        BoxGeometryError: the file cannot be read, or the model is not one link of unrotated boxes with a floor
            and four walls.
    """
    if isinstance(urdf, Path):
        try:
            urdf = UrdfDocument.read(urdf)
        except UrdfError as e:
            raise BoxGeometryError(box, str(e)) from None
    parts = _collision_boxes(box, urdf, scale)
    cx = (min(p[0] for p in parts) + max(p[3] for p in parts)) / 2
    cy = (min(p[1] for p in parts) + max(p[4] for p in parts)) / 2
    x0, x1, y0, y1 = -np.inf, np.inf, -np.inf, np.inf
    floor, rim = -np.inf, -np.inf
    for px0, py0, _pz0, px1, py1, pz1 in parts:
        over_x, over_y = px0 <= cx <= px1, py0 <= cy <= py1
        if over_x and over_y:
            floor = max(floor, pz1)
            continue
        rim = max(rim, pz1)
        if over_y:
            x0, x1 = (max(x0, px1), x1) if px1 < cx else (x0, min(x1, px0))
        elif over_x:
            y0, y1 = (max(y0, py1), y1) if py1 < cy else (y0, min(y1, py0))
    found = (x0, y0, floor, x1, y1, rim)
    if not all(np.isfinite(found)) or not (x0 < x1 and y0 < y1 and floor < rim):
        raise BoxGeometryError(box, f"{urdf} does not look like a floor with four walls around it")
    r = [round(float(v), 9) for v in found]
    return (r[0], r[1], r[2], r[3], r[4], r[5])
