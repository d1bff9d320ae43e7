"""Planar lidar: batched ray casts from a robot link, as a LaserScan-shaped record."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..backend import Array, Backend
from ..geometry import quat_to_matrix
from ..world.models import Lidar


@dataclass(frozen=True)
class Scan:
    """One lidar scan, laid out as ``sensor_msgs/LaserScan`` (angles counter-clockwise about the link's z).

    Attributes:
        robot: The robot carrying the lidar.
        lidar: The lidar's name.
        frame: The link the lidar sits on (``header.frame_id``).
        stamp: Simulation time of the scan [s].
        angle_min: Angle of the first beam [rad].
        angle_max: Angle of the last beam [rad].
        angle_increment: Angle between beams [rad].
        range_min: Minimum valid range [m].
        range_max: Maximum range [m]; beams with no hit are ``inf``.
        scan_time: Time between scans [s].
        ranges: (beams,) ranges [m].
    """

    robot: str
    lidar: str
    frame: str
    stamp: float
    angle_min: float
    angle_max: float
    angle_increment: float
    range_min: float
    range_max: float
    scan_time: float
    ranges: Array

    def fields(self, frame: str, stamp_ns: int) -> dict[str, object]:
        """The ``sensor_msgs/LaserScan`` fields of this scan in TF frame ``frame``, stamped ``stamp_ns`` [ns]
        (ranges as float32)."""
        return {"header": {"stamp": stamp_ns, "frame_id": frame}, "angle_min": self.angle_min,
                "angle_max": self.angle_max, "angle_increment": self.angle_increment, "time_increment": 0.0,
                "scan_time": self.scan_time, "range_min": self.range_min, "range_max": self.range_max,
                "ranges": np.ascontiguousarray(self.ranges, dtype=np.float32)}


class LidarSensor:
    """A lidar of a robot; :meth:`scan` casts every beam at once through the backend."""

    def __init__(self, robot: str, model: Lidar, timestep: float, seed: int) -> None:
        self.robot = robot
        self.model = model
        full_circle = model.fov >= 2 * math.pi - 1e-6
        n = model.beams
        self.angle_min = -model.fov / 2
        self.increment = model.fov / n if full_circle or n == 1 else model.fov / (n - 1)
        self.angle_max = self.angle_min + self.increment * (n - 1)
        angles = self.angle_min + self.increment * np.arange(n)
        self._local = np.stack([np.cos(angles), np.sin(angles), np.zeros(n)], axis=1)
        self.period_steps = max(1, round(1.0 / (model.rate * timestep)))
        self._dt = timestep
        self._rng = np.random.default_rng(seed)
        self.last: Scan | None = None

    def scan(self, backend: Backend, stamp: float) -> Scan:
        """Cast the beams from the link's current pose and return the scan (also kept in ``last``)."""
        pos, quat = backend.get_pose(self.robot, self.model.link)
        dirs = self._local @ quat_to_matrix(quat).T
        rmin, rmax = self.model.range
        ranges = backend.ray_cast(pos, dirs, rmax, exclude=self.robot)
        if self.model.noise > 0:
            hit = np.isfinite(ranges)
            ranges = ranges.copy()
            ranges[hit] += self._rng.normal(0.0, self.model.noise, int(hit.sum()))
        ranges[ranges > rmax] = np.inf
        self.last = Scan(self.robot, self.model.name, self.model.link, stamp, self.angle_min, self.angle_max,
                         self.increment, rmin, rmax, self.period_steps * self._dt, ranges)
        return self.last
