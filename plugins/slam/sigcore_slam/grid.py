"""A log-odds occupancy grid laid out like ``nav_msgs/OccupancyGrid``, updated by vectorised ray tracing."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


class OccupancyGrid:
    """Log-odds occupancy of square cells, ``nav_msgs/OccupancyGrid`` layout.

    Cell ``(row, col)`` covers ``origin + (col, row) * resolution`` to one cell further: rows run along +y, columns
    along +x, and :meth:`data` flattened in C order is ``OccupancyGrid.data``.

    Args:
        width: Number of columns (cells along x).
        height: Number of rows (cells along y).
        resolution: Cell size [m].
        origin: Map-frame (x, y) [m] of the corner of cell (0, 0).
        hit: Log-odds added to the cell a beam ends in.
        miss: Log-odds removed from each cell a beam crosses before its end.
        clamp: Log-odds are kept in ``[-clamp, clamp]`` (so the map can still change).
    """

    def __init__(self, width: int, height: int, resolution: float, origin: tuple[float, float],
                 hit: float = 0.85, miss: float = 0.4, clamp: float = 5.0) -> None:
        self.width = width
        self.height = height
        self.resolution = resolution
        self.origin = (float(origin[0]), float(origin[1]))
        self.hit = np.float32(hit)
        self.miss = np.float32(miss)
        self.clamp = np.float32(clamp)
        self.log_odds = np.zeros((height, width), np.float32)
        self.known = np.zeros((height, width), bool)
        self._stamp = np.zeros(height * width, np.int64)  # scratch of trace(): one update per cell and scan
        # numba is imported here, not with the plugin (about 0.13 s: a world without SLAM must not pay it), and the
        # kernel loaded (or, the first time on a machine, compiled) now rather than during the first scan
        from .trace import trace

        self._trace = trace
        none_f, none_i, none_b = np.zeros(0, np.float32), np.zeros(0, np.int64), np.zeros(0, bool)
        trace(self.log_odds.reshape(-1), self.known.reshape(-1), self._stamp, 0, width, np.float32(0.0),
              np.float32(0.0), none_f, none_f, none_i, none_i, none_b, none_b, self.miss, self.hit, self.clamp)
        self.updates = 0
        self._cache: tuple[int, npt.NDArray[np.int8]] | None = None

    def integrate(self, sensor: tuple[float, float], ends: Array, hits: npt.NDArray[np.bool_]) -> None:
        """Trace one scan: cells crossed by each beam become freer, the end cells of hitting beams more occupied.

        Each beam visits every cell of its major axis once (a DDA in cell units, like Bresenham), so a scan
        costs about ``sum(range) / resolution`` samples; beams are clipped to the grid first. A cell crossed by
        several beams of one scan is updated once. Nothing happens while the sensor is outside the grid.

        Args:
            sensor: Map-frame (x, y) [m] of the beams' origin.
            ends: (n, 2) map-frame beam ends [m]: the hit point, or the point at maximum range for no hit.
            hits: (n,) whether each beam hit something (only those mark their end cell occupied).
        """
        res, width, height = self.resolution, self.width, self.height
        u0 = (sensor[0] - self.origin[0]) / res
        v0 = (sensor[1] - self.origin[1]) / res
        if not (0.0 <= u0 < width and 0.0 <= v0 < height):
            return
        du = (ends[:, 0] - self.origin[0]) / res - u0
        dv = (ends[:, 1] - self.origin[1]) / res - v0
        # clip every beam to the grid (a margin of a thousandth of a cell keeps float32 samples inside)
        with np.errstate(divide="ignore", invalid="ignore"):
            tu = np.where(du > 0, (width - 1e-3 - u0) / du, np.where(du < 0, -u0 / du, np.inf))
            tv = np.where(dv > 0, (height - 1e-3 - v0) / dv, np.where(dv < 0, -v0 / dv, np.inf))
        reach = np.minimum(np.minimum(tu, tv), 1.0)
        end_inside = reach >= 1.0
        du *= reach
        dv *= reach
        steps = np.ceil(np.maximum(np.abs(du), np.abs(dv))).astype(np.int32)
        end_cells = np.floor(v0 + dv).astype(np.int32) * width + np.floor(u0 + du).astype(np.int32)
        per_step = 1.0 / np.maximum(steps, 1)
        samples = steps + ~end_inside  # a clipped beam also frees the border cell it ends in
        self._trace(self.log_odds.reshape(-1), self.known.reshape(-1), self._stamp, 2 * self.updates + 2, width,
              np.float32(u0), np.float32(v0), (du * per_step).astype(np.float32),
              (dv * per_step).astype(np.float32), samples.astype(np.int64), end_cells.astype(np.int64), end_inside,
              hits & end_inside, self.miss, self.hit, self.clamp)
        self.updates += 1

    def data(self) -> npt.NDArray[np.int8]:
        """(height, width) int8 occupancy: -1 unknown, else ``round(100 * p)`` with p the occupancy probability.

        Computed when the grid changed since the last call; treat the result as read-only.
        """
        if self._cache is None or self._cache[0] != self.updates:
            prob = 1.0 / (1.0 + np.exp(-self.log_odds))
            out = np.rint(prob * 100.0).astype(np.int8)
            out[~self.known] = -1
            self._cache = (self.updates, out)
        return self._cache[1]

    def cell_centres(self) -> tuple[Array, Array]:
        """Map-frame x (width,) and y (height,) [m] of the cell centres."""
        res = self.resolution
        xs: Array = self.origin[0] + (np.arange(self.width, dtype=np.float64) + 0.5) * res
        ys: Array = self.origin[1] + (np.arange(self.height, dtype=np.float64) + 0.5) * res
        return xs, ys
