"""Batched ray casting for lidars with ``mj_multiRay``, passing through one excluded entity.

``mj_multiRay`` can exclude one body only, and a robot has many. Rays here see geom group 0 only (every
collision geom; visual-only geoms are in group 2); to exclude an entity, its geoms are moved to group 5 for
the duration of the cast (one vectorised write of ``model.geom_group`` and one to restore it), so the rays
pass through all of its bodies at no extra cost, whatever the number of robots.
"""

from __future__ import annotations

import mujoco
import numpy as np
import numpy.typing as npt

from .layout import Ints
from .plan import GROUP_COLLISION, GROUP_RAY_EXCLUDED

Array = npt.NDArray[np.float64]


class RayCaster:
    """Casts fans of rays against a model's collision geoms; keeps its output buffers between calls."""

    def __init__(self) -> None:
        self._mask = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
        self._mask[GROUP_COLLISION] = 1
        self._geomid = np.zeros(0, dtype=np.int32)
        self._dist = np.zeros(0)
        self.hit_geoms = np.zeros(0, dtype=np.int32)

    def cast(self, model: mujoco.MjModel, data: mujoco.MjData, origin: Array, directions: Array,
             max_range: float, exclude: Ints | None) -> Array:
        """Distances [m] along (N, 3) unit ``directions`` from ``origin`` to the first collision geom.

        Args:
            model: The model (its ``geom_group`` is changed and restored during the call).
            data: Data with current geom poses.
            origin: (3,) world point [m].
            directions: (N, 3) unit vectors.
            max_range: Hits beyond this [m] count as none.
            exclude: Geom ids the rays pass through, or ``None``.

        Returns:
            (N,) distances [m], ``inf`` where nothing is hit within ``max_range``.
        """
        vec = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1)
        n = vec.shape[0] // 3
        if self._dist.shape[0] < n:
            self._geomid = np.zeros(n, dtype=np.int32)
            self._dist = np.zeros(n)
        geomid, dist = self._geomid[:n], self._dist[:n]
        pnt = np.ascontiguousarray(origin, dtype=np.float64)
        if exclude is not None and exclude.size:
            saved = model.geom_group[exclude].copy()
            model.geom_group[exclude] = GROUP_RAY_EXCLUDED
            try:
                mujoco.mj_multiRay(model, data, pnt, vec, self._mask, 1, -1, geomid, dist, None, n, max_range)
            finally:
                model.geom_group[exclude] = saved
        else:
            mujoco.mj_multiRay(model, data, pnt, vec, self._mask, 1, -1, geomid, dist, None, n, max_range)
        out = dist.copy()
        out[(geomid < 0) | (out > max_range)] = np.inf
        self.hit_geoms = np.where(np.isfinite(out), geomid, -1)  # the geom each ray hit first (-1: none)
        return out
