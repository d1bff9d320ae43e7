"""The core lidar as SLAM consumes it: LaserScan-shaped fields and ranges in a known box room."""

from __future__ import annotations

import math

import numpy as np
from slam_room import ROBOT, room_world

from sigcore.geometry import quat_yaw
from sigcore.sim import Simulation
from sigcore.sim.lidar import Scan

X_MIN, X_MAX, Y_MIN, Y_MAX = -2.0, 3.0, -1.5, 1.5  # inner faces of the walls
PILLAR = (1.35, 1.65, 0.65, 0.95)  # x0, x1, y0, y1


def _box_exit(ox: float, oy: float, dx: float, dy: float, box: tuple[float, float, float, float]) -> float:
    """Distance from inside ``box`` along (dx, dy) to its boundary."""
    x0, x1, y0, y1 = box
    tx = (x1 - ox) / dx if dx > 0 else (x0 - ox) / dx if dx < 0 else math.inf
    ty = (y1 - oy) / dy if dy > 0 else (y0 - oy) / dy if dy < 0 else math.inf
    return min(tx, ty)


def _box_entry(ox: float, oy: float, dx: float, dy: float, box: tuple[float, float, float, float]) -> float:
    """Distance from outside ``box`` along (dx, dy) to where the ray enters it (inf if it misses)."""
    x0, x1, y0, y1 = box
    lo, hi = 0.0, math.inf
    for o, d, a, b in ((ox, dx, x0, x1), (oy, dy, y0, y1)):
        if abs(d) < 1e-12:
            if not a <= o <= b:
                return math.inf
            continue
        t0, t1 = sorted(((a - o) / d, (b - o) / d))
        lo, hi = max(lo, t0), min(hi, t1)
    return lo if lo <= hi else math.inf


def _analytic(sim: Simulation, scan: Scan) -> np.ndarray:
    pos, quat = sim.backend.get_pose(ROBOT, scan.frame)
    yaw = quat_yaw(quat)
    out = []
    for i in range(len(scan.ranges)):
        a = yaw + scan.angle_min + i * scan.angle_increment
        dx, dy = math.cos(a), math.sin(a)
        out.append(min(_box_exit(pos[0], pos[1], dx, dy, (X_MIN, X_MAX, Y_MIN, Y_MAX)),
                       _box_entry(pos[0], pos[1], dx, dy, PILLAR)))
    return np.array(out)


def test_scan_fields_are_laserscan_shaped() -> None:
    """Scans come every 0.1 s stamped with the sim time, from the lidar link, with LaserScan angles in rad."""
    sim = Simulation(room_world(None), "mujoco")
    scans: list[Scan] = []
    sim.events.subscribe("scan", scans.append)
    sim.step(150)
    assert [round(s.stamp, 9) for s in scans] == [0.1, 0.2, 0.3]
    scan = scans[-1]
    assert (scan.robot, scan.lidar, scan.frame) == (ROBOT, "base_scan", "base_laser_link")
    assert math.isclose(scan.angle_min, -math.pi, abs_tol=1e-6)  # fov="6.283185" in the file
    assert math.isclose(scan.angle_increment, 2 * math.pi / 360, rel_tol=1e-6)
    assert math.isclose(scan.angle_max, scan.angle_min + 359 * scan.angle_increment)
    assert (scan.range_min, scan.range_max) == (0.05, 8.0)
    assert math.isclose(scan.scan_time, 0.1)
    assert scan.ranges.shape == (360,)


def test_ranges_match_the_room_within_1cm() -> None:
    """Every beam's range [m] equals the analytic distance to the room's walls or the pillar within 1 cm."""
    sim = Simulation(room_world(None), "mujoco")
    sim.step(50)
    scan = sim.entities.lidars[0].last
    assert scan is not None
    expected = _analytic(sim, scan)
    assert np.all(np.isfinite(scan.ranges))
    assert np.max(np.abs(scan.ranges - expected)) < 0.01
    # the pillar is seen: some beams are much shorter than the walls behind it
    assert np.sum(expected < 1.6) > 5
