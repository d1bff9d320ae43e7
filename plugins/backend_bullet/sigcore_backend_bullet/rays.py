"""Batched lidar rays with ``rayTestBatch``, passing through one excluded entity.

PyBullet 3.2.7's ``rayTestBatch`` has no exclusion list, and changing an entity's collision filter group for
the duration of a cast would remove and re-add its links to the broadphase (``setCollisionFilterGroupMask``),
which changes the order of contact pairs: the lidar would change the physics. So rays are cast against
everything (``collisionFilterMask`` = the ray bit, which every link has, with collision on or off), and the few
rays whose first hit is a link of the excluded entity are cast again from where they leave that link's
axis-aligned bounding box (``getAABB``), up to :data:`MAX_PASSES` times. Stepping just past the hit point does
not work: a ray starting inside a URDF link (a compound shape) hits it at distance 0. The price: something
else inside that box, beyond the excluded link's surface, is not seen (e.g. a wall within a few centimetres of
the robot's arm).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from operator import itemgetter

import numpy as np
import numpy.typing as npt
import pybullet as pb

from .layout import RAY_MASK

Array = npt.NDArray[np.float64]

MAX_PASSES = 8
"""Re-casts through the excluded entity (each one passes one of its surfaces)."""
STEP_THROUGH = 1e-5
"""How far beyond an excluded link's bounding box the next pass starts [m]."""
_BATCH = 16384
"""``MAX_RAY_INTERSECTION_BATCH_SIZE`` of PyBullet 3.2.7."""
_BODY, _LINK, _FRACTION = itemgetter(0), itemgetter(1), itemgetter(2)
"""Fields of a ``rayTestBatch`` result."""


def cast(client: int, origin: Array, directions: Array, max_range: float, exclude: int | None,
         links: list[int] | None = None) -> Array:
    """Distances [m] along (N, 3) unit ``directions`` from ``origin`` to the first surface.

    Args:
        client: PyBullet client id.
        origin: (3,) world point [m].
        directions: (N, 3) unit vectors.
        max_range: Hits beyond this [m] count as none.
        exclude: Body id the rays pass through, or ``None``.
        links: Link indices of ``exclude`` (base ``-1`` included); rays start where they leave the bounding
            boxes of those that contain ``origin`` (a lidar inside its own housing).

    Returns:
        (N,) distances [m], ``inf`` where nothing is hit within ``max_range``.
    """
    dirs = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    n = dirs.shape[0]
    o = np.asarray(origin, dtype=np.float64)
    out = np.full(n, np.inf)
    travelled = np.zeros(n)
    if exclude is not None and links:
        ox, oy, oz = (float(v) for v in o)
        boxes = []
        for index in links:  # plain comparisons: numpy costs about 8 µs a link here, 20 links a scan
            lo, hi = pb.getAABB(exclude, index, physicsClientId=client)
            if lo[0] <= ox <= hi[0] and lo[1] <= oy <= hi[1] and lo[2] <= oz <= hi[2]:
                boxes.append((lo, hi))
        for box in boxes:  # a box inside another one that holds the origin is left first by every ray
            if not any(other is not box and _within(box, other) for other in boxes):
                exit_ = _slab_exit(o, dirs, np.array(box[0]), np.array(box[1])) + STEP_THROUGH
                travelled = np.maximum(travelled, exit_)
    ends = (o + dirs * max_range).tolist()  # every pass of a ray ends there: [start, end] is what remains
    todo = np.arange(n)
    for _ in range(MAX_PASSES):
        if todo.size == 0:
            break
        part = travelled[todo]
        starts = (o + dirs[todo] * part[:, None]).tolist() if part.any() else [o.tolist()] * todo.size
        body, hit_link, fraction = _batch(client, starts, ends if todo.size == n else [ends[i] for i in todo])
        hit = body >= 0
        through = hit & (body == exclude) if exclude is not None else None
        final = hit & ~through if through is not None else hit
        out[todo[final]] = (part + fraction * (max_range - part))[final]
        if through is None or not through.any():
            break
        again = todo[through]
        exits = np.empty(again.size)
        for k in np.unique(hit_link[through]):
            rows = hit_link[through] == k
            box_lo, box_hi = pb.getAABB(exclude, int(k), physicsClientId=client)
            exits[rows] = _slab_exit(o + dirs[again[rows]] * travelled[again[rows]][:, None], dirs[again[rows]],
                                     np.array(box_lo), np.array(box_hi))
        travelled[again] += np.maximum(exits, 0.0) + STEP_THROUGH
        todo = again[travelled[again] < max_range]
    out[out > max_range] = np.inf
    return out


def first_hits(client: int, origin: Array, directions: Array, max_range: float, among: Collection[int],
               passes: int = 4 * MAX_PASSES) -> tuple[Array, npt.NDArray[np.int64]]:
    """Distances [m] along (N, 3) unit ``directions`` from ``origin`` to the first surface of a body in ``among``,
    and that body (-1: none within ``max_range``). A ray that hits another body is cast again from where it leaves
    that link's bounding box (as :func:`cast` passes the excluded entity), up to ``passes`` times."""
    dirs = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    n = dirs.shape[0]
    o = np.asarray(origin, dtype=np.float64)
    out = np.full(n, np.inf)
    hit_body = np.full(n, -1, dtype=np.int64)
    travelled = np.zeros(n)
    wanted = np.fromiter(among, dtype=np.int64)
    todo = np.arange(n)
    for _ in range(passes):
        if todo.size == 0:
            break
        part = travelled[todo]
        starts = (o + dirs[todo] * part[:, None]).tolist()
        body, link, fraction = _batch(client, starts, (o + dirs[todo] * max_range).tolist())
        hit = body >= 0
        final = hit & np.isin(body, wanted)
        out[todo[final]] = (part + fraction * (max_range - part))[final]
        hit_body[todo[final]] = body[final]
        through = hit & ~final
        again = todo[through]
        exits = np.empty(again.size)
        for i, (b, k) in enumerate(zip(body[through].tolist(), link[through].tolist(), strict=True)):
            lo, hi = pb.getAABB(b, k, physicsClientId=client)
            start = o + dirs[again[i]] * travelled[again[i]]
            exits[i] = _slab_exit(start[None, :], dirs[again[i]][None, :], np.array(lo), np.array(hi))[0]
        travelled[again] += np.maximum(exits, 0.0) + STEP_THROUGH
        todo = again[travelled[again] < max_range]
    far = out > max_range
    out[far], hit_body[far] = np.inf, -1
    return out, hit_body


def _within(inner: tuple[Sequence[float], Sequence[float]], outer: tuple[Sequence[float], Sequence[float]]) -> bool:
    """Whether the box ``inner`` (lower and upper corner) lies in ``outer``."""
    return all(a <= b for a, b in zip(outer[0], inner[0], strict=True)) and all(
        a <= b for a, b in zip(inner[1], outer[1], strict=True))


def _slab_exit(starts: Array, dirs: Array, lo: Array, hi: Array) -> Array:
    """Distance [m] along each ray from its start (inside the box; (N, 3) or one (3,) point) to where it leaves the
    box ``lo``..``hi``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / dirs  # a zero component gives +-inf: that slab is never left
        far = np.fmax((hi - starts) * inv, (lo - starts) * inv)  # fmax: 0 * inf (a start on a face) is NaN
    return np.min(far, axis=1)


def _batch(client: int, starts: list[list[float]], ends: list[list[float]]) -> tuple[
        npt.NDArray[np.int64], npt.NDArray[np.int64], Array]:
    results: list[tuple[int, int, float]] = []
    for i in range(0, len(starts), _BATCH):
        results += pb.rayTestBatch(starts[i:i + _BATCH], ends[i:i + _BATCH], collisionFilterMask=RAY_MASK,
                                   physicsClientId=client)
    n = len(results)
    bodies = np.fromiter(map(_BODY, results), dtype=np.int64, count=n)
    links = np.fromiter(map(_LINK, results), dtype=np.int64, count=n)
    fractions = np.fromiter(map(_FRACTION, results), dtype=np.float64, count=n)
    return bodies, links, fractions
