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
    out = np.full(n, np.inf)
    start = np.broadcast_to(np.asarray(origin, dtype=np.float64), (n, 3)).copy()
    travelled = np.zeros(n)
    if exclude is not None and links:
        o = np.asarray(origin, dtype=np.float64)
        for index in links:
            lo, hi = (np.array(v) for v in pb.getAABB(exclude, index, physicsClientId=client))
            if np.all(lo <= o) and np.all(o <= hi):
                travelled = np.maximum(travelled, _slab_exit(start, dirs, lo, hi) + STEP_THROUGH)
        start += dirs * travelled[:, None]
    todo = np.arange(n)
    for _ in range(MAX_PASSES):
        if todo.size == 0:
            break
        remaining = max_range - travelled[todo]
        ends = start[todo] + dirs[todo] * remaining[:, None]
        body, hit_link, fraction = _batch(client, start[todo], ends)
        hit = body >= 0
        dist = travelled[todo] + fraction * remaining
        through = hit & (body == exclude) if exclude is not None else np.zeros_like(hit)
        final = hit & ~through
        out[todo[final]] = dist[final]
        again = todo[through]
        if again.size == 0:
            break
        assert exclude is not None
        exits = np.empty(again.size)
        for k in np.unique(hit_link[through]):
            rows = hit_link[through] == k
            box_lo, box_hi = pb.getAABB(exclude, int(k), physicsClientId=client)
            exits[rows] = _slab_exit(start[again[rows]], dirs[again[rows]], np.array(box_lo), np.array(box_hi))
        travelled[again] += np.maximum(exits, 0.0) + STEP_THROUGH
        start[again] = np.asarray(origin) + dirs[again] * travelled[again][:, None]
        todo = again[travelled[again] < max_range]
    out[out > max_range] = np.inf
    return out


def _slab_exit(starts: Array, dirs: Array, lo: Array, hi: Array) -> Array:
    """Distance [m] along each ray from its start to where it leaves the box ``lo``..``hi``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        far = np.where(dirs > 0, (hi - starts) / dirs, np.where(dirs < 0, (lo - starts) / dirs, np.inf))
    return np.min(far, axis=1)


def _batch(client: int, starts: Array, ends: Array) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], Array]:
    results: list[tuple[int, int, float]] = []
    for i in range(0, starts.shape[0], _BATCH):
        results += pb.rayTestBatch(starts[i:i + _BATCH].tolist(), ends[i:i + _BATCH].tolist(),
                                   collisionFilterMask=RAY_MASK, physicsClientId=client)
    bodies = np.fromiter((r[0] for r in results), dtype=np.int64, count=len(results))
    links = np.fromiter((r[1] for r in results), dtype=np.int64, count=len(results))
    fractions = np.fromiter((r[2] for r in results), dtype=np.float64, count=len(results))
    return bodies, links, fractions
