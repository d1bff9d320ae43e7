"""The viewer's overlays drawn over the scene (names, TF frames, lidar scans, contacts, the map): which there are and
whether each is on at the start, and the geometry a snapshot carries for them - lidar scans as world points, contact
markers, an occupancy grid as a floor image - for a live run and for a recording's playback alike.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.geometry import quat_to_matrix

from .scenebuild import SceneLayout

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

OVERLAYS = {"names": True, "frames": False, "scan": False, "contacts": False, "map": True}
"""The overlays and whether each is on at the start."""


def scan_points(layout: SceneLayout, scans: Iterable[dict[str, Any]], poses: np.ndarray) -> np.ndarray:
    """``sensor_msgs/LaserScan`` values as (n, 3) world points, each from the pose of its frame in ``poses`` (the
    layout's frames); scans of a frame the layout has not are left out."""
    out = [np.zeros((0, 3))]
    for scan in scans:
        index = layout.index.get(str(scan.get("header", {}).get("frame_id", "")))
        if index is None:
            continue
        ranges = np.asarray(scan["ranges"], dtype=float)
        angles = scan["angle_min"] + scan["angle_increment"] * np.arange(len(ranges))
        ok = np.isfinite(ranges) & (ranges < scan["range_max"]) & (ranges >= scan["range_min"])
        local = np.stack([ranges[ok] * np.cos(angles[ok]), ranges[ok] * np.sin(angles[ok]),
                          np.zeros(int(ok.sum()))], axis=1)
        out.append(local @ quat_to_matrix(poses[index, 3:]).T + poses[index, :3])
    return np.vstack(out)


def contact_points(sim: Simulation) -> np.ndarray:
    """A marker at each part touching another entity (the floor contacts of wheels and casters left out)."""
    points = []
    for entity, part, other in sim.contact_triples():
        if other == "ground" and sim.entities.is_robot(entity) and part in sim.entities.rolling_parts(entity):
            continue
        try:
            pos, _ = sim.backend.get_pose(entity, None if part == "main" else part)
        except Exception:  # a part the backend no longer has (deleted meanwhile): no marker
            continue
        points.append(pos)
    return np.array(points, dtype=float).reshape(-1, 3)


def grid_image(grid: dict[str, Any]) -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray] | None:
    """An occupancy grid as a floor image: free white, occupied black, unknown grey."""
    info = grid.get("info", {})
    w, h, res = int(info.get("width", 0)), int(info.get("height", 0)), float(info.get("resolution", 0.0))
    data = np.asarray(grid.get("data", []), dtype=np.int16)
    if w <= 0 or h <= 0 or res <= 0 or data.size != w * h:
        return None
    cells = data.reshape(h, w)
    shade = np.where(cells < 0, 200, 255 - (np.clip(cells, 0, 100) * 255 // 100)).astype(np.uint8)
    image = np.repeat(np.flipud(shade)[:, :, None], 3, axis=2)  # row 0 of the grid is at the origin's y
    origin = info.get("origin", {})
    p, o = origin.get("position", {}), origin.get("orientation", {})
    quat = np.array([o.get("w", 1.0), o.get("x", 0.0), o.get("y", 0.0), o.get("z", 0.0)], dtype=float)
    centre = np.array([p.get("x", 0.0), p.get("y", 0.0), p.get("z", 0.0)]) + \
        quat_to_matrix(quat) @ np.array([w * res / 2, h * res / 2, 0.0])
    centre[2] += 0.003  # just above the floor
    return image, w * res, h * res, centre, quat


def no_grid() -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray]:
    """No map at this moment: an empty image (the map shown is removed)."""
    return np.zeros((0, 0, 3), dtype=np.uint8), 0.0, 0.0, np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
