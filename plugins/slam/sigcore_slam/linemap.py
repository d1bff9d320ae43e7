"""Point-to-line refinement of kiss-icp's pose against a map of local line statistics.

kiss-icp aligns points to points. With a 1 degree scanner that turns in place, a scan's beams land between the
previous scans' beams, and point-to-point matching pulls the heading towards a whole number of beams: a few mrad
per turn, which over a 10 m room is centimetres. This module removes that bias: the map keeps, per square cell,
the count, mean and covariance of every registered point; a cell whose points lie along a line (a wall, a box face)
constrains a new point only across the line, other cells (corners, table legs) in every direction (a
normal-distributions transform with line cells made one-dimensional). A few Gauss-Newton steps move kiss-icp's
estimate to the minimum.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from .se2 import Pose2

Array = npt.NDArray[np.float64]

LINE_RATIO = 9.0
"""A cell is a line when its covariance's large eigenvalue exceeds this many times the small one."""


class LineMap:
    """Per-cell point statistics on a square grid, and the point-to-line alignment of scans against them.

    Args:
        width: Cells along x.
        height: Cells along y.
        cell: Cell size [m] (kiss-icp's voxel size is a good choice: a few points of each scan per cell).
        origin: Map-frame (x, y) [m] of the corner of cell (0, 0).
        sigma: Point noise [m] added to every cell's covariance (keeps thin lines well conditioned).
        min_points: Cells with fewer points are not used.
    """

    def __init__(self, width: int, height: int, cell: float, origin: tuple[float, float], sigma: float = 0.01,
                 min_points: int = 5) -> None:
        self.width = width
        self.height = height
        self.cell = cell
        self.origin = origin
        self.var = sigma * sigma
        self.min_points = min_points
        self.sums = np.zeros((6, width * height))  # n, x, y, xx, xy, yy

    def _index(self, x: Array, y: Array) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.bool_]]:
        col = np.floor((x - self.origin[0]) / self.cell).astype(np.int64)
        row = np.floor((y - self.origin[1]) / self.cell).astype(np.int64)
        inside = (col >= 0) & (col < self.width) & (row >= 0) & (row < self.height)
        return np.where(inside, row * self.width + col, 0), inside

    def add(self, points: Array) -> None:
        """Accumulate (n, 2) map-frame points [m]."""
        index, inside = self._index(points[:, 0], points[:, 1])
        p, index = points[inside], index[inside]
        if not len(p):
            return
        x, y = p[:, 0], p[:, 1]
        for k, values in enumerate((np.ones_like(x), x, y, x * x, x * y, y * y)):
            np.add.at(self.sums[k], index, values)

    def _associate(self, x: Array, y: Array) -> tuple[npt.NDArray[np.bool_], Array, Array, Array, Array, Array]:
        """Cells of map points: (used mask, mean x, mean y, information xx, xy, yy) of the used points."""
        index, inside = self._index(x, y)
        n = self.sums[0, index]
        ok = inside & (n >= self.min_points)
        i, n = index[ok], n[ok]
        mx, my = self.sums[1, i] / n, self.sums[2, i] / n
        cxx = self.sums[3, i] / n - mx * mx
        cxy = self.sums[4, i] / n - mx * my
        cyy = self.sums[5, i] / n - my * my
        half = np.sqrt(np.maximum(((cxx - cyy) / 2) ** 2 + cxy * cxy, 0.0))
        big = (cxx + cyy) / 2 + half
        small = np.maximum((cxx + cyy) / 2 - half, 0.0)
        theta = 0.5 * np.arctan2(2 * cxy, cxx - cyy)  # direction of the large eigenvalue: along the line
        tx, ty = np.cos(theta), np.sin(theta)
        w_across = 1.0 / (small + self.var)
        w_along = np.where(big > LINE_RATIO * small, 0.0, 1.0 / (big + self.var))
        return (ok, mx, my, w_across * ty * ty + w_along * tx * tx, (w_along - w_across) * tx * ty,
                w_across * tx * tx + w_along * ty * ty)

    def align(self, pose: Pose2, points: Array, rounds: int = 2, steps: int = 3) -> tuple[Pose2, int]:
        """Refine ``pose`` (``map_T_scan``) so that the (n, 2) scan-frame ``points`` fit the map's cells.

        Each of ``rounds`` associates every point with the cell it falls in, then takes up to ``steps``
        Gauss-Newton steps (Cauchy-weighted) with those cells.

        Returns:
            The refined pose and the number of points that found a cell (0: ``pose`` unchanged).
        """
        x, y, yaw = pose.x, pose.y, pose.yaw
        px, py = points[:, 0], points[:, 1]
        terms = np.empty((9, len(points)))
        used = 0
        for _ in range(rounds):
            c, s = math.cos(yaw), math.sin(yaw)
            ok, mx, my, oxx, oxy, oyy = self._associate(c * px - s * py + x, s * px + c * py + y)
            used = len(mx)
            if used < 3:
                return pose, 0
            qx, qy = px[ok], py[ok]
            t = terms[:, :used]
            moved = 0.0
            for _ in range(steps):
                c, s = math.cos(yaw), math.sin(yaw)
                rx, ry = c * qx - s * qy, s * qx + c * qy
                ex, ey = rx + x - mx, ry + y - my
                jx, jy = -ry, rx  # derivative of the map point with respect to yaw
                m2 = ex * (oxx * ex + oxy * ey) + ey * (oxy * ex + oyy * ey)
                robust = 1.0 / (1.0 + m2 / 9.0)  # Cauchy weights: points 3 sigma off count half
                a, b, d = robust * oxx, robust * oxy, robust * oyy
                aj, bj = a * jx + b * jy, b * jx + d * jy
                ga, gb = a * ex + b * ey, b * ex + d * ey
                # the 9 sums of the normal equations in one pass: H = [[a, b, aj], [b, d, bj], [aj, bj, jj]]
                t[0], t[1], t[2], t[3], t[4] = a, b, d, aj, bj
                t[5], t[6], t[7] = jx * aj + jy * bj, ga, gb
                t[8] = jx * ga + jy * gb
                sa, sb, sd, saj, sbj, sjj, g0, g1, g2 = t.sum(axis=1).tolist()
                step = _solve3((sa + 1e-9, sb, saj, sd + 1e-9, sbj, sjj + 1e-9), (-g0, -g1, -g2))
                if step is None:
                    return pose, 0
                x, y, yaw = x + step[0], y + step[1], yaw + step[2]
                moved = abs(step[0]) + abs(step[1]) + abs(step[2])
                if moved < 1e-5:
                    break
            if moved < 1e-5:
                break
        return Pose2(x, y, math.atan2(math.sin(yaw), math.cos(yaw))), used


def _solve3(h: tuple[float, float, float, float, float, float],
            g: tuple[float, float, float]) -> tuple[float, float, float] | None:
    """Solve the symmetric 3x3 system ``H x = g`` (``h`` = H's upper triangle row by row) by Cramer's rule; ``None``
    when H is singular (plain floats: ``np.linalg.solve`` costs about 10 µs a call here)."""
    a, b, c, d, e, f = h
    m00, m01, m02 = d * f - e * e, c * e - b * f, b * e - c * d
    det = a * m00 + b * m01 + c * m02
    if not math.isfinite(det) or abs(det) < 1e-300:
        return None
    m11, m12, m22 = a * f - c * c, b * c - a * e, a * d - b * b
    g0, g1, g2 = g
    return ((m00 * g0 + m01 * g1 + m02 * g2) / det, (m01 * g0 + m11 * g1 + m12 * g2) / det,
            (m02 * g0 + m12 * g1 + m22 * g2) / det)
