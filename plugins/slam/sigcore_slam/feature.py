"""The ``slam`` feature: kiss-icp registration of a robot's lidar scans, ``map -> odom``, an occupancy grid."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from sigcore.feature import Feature
from sigcore.geometry import quat_to_matrix, quat_yaw
from sigcore.publish import Publication, planar_quaternion, transform_fields
from sigcore.sim.frames import WORLD
from sigcore.sim.lidar import LidarSensor, Scan
from sigcore.sim.odometry import OdometryState
from sigcore.world.exceptions import FieldError
from sigcore.world.models import Robot

from . import api
from .config import SlamConfig
from .grid import OccupancyGrid
from .linemap import LineMap
from .mapfile import save_map
from .registration import ScanMatcher
from .se2 import Pose2

if TYPE_CHECKING:
    from sigcore.api.table import ApiEntry
    from sigcore.sim.simulation import Simulation

MIN_POINTS = 20
"""Scans with fewer valid points are not registered: the pose follows the wheel odometry (or stays)."""

REFINE_POINTS = 200
"""The refinement uses at most about this many of a scan's points (every k-th): more add time, not accuracy."""

MAP_RATE = 1.0
"""``/map`` is published at most this often [Hz of simulated time], when the grid changed."""

MAX_CORRECTION = (0.2, 0.1)
"""A refinement that moves kiss-icp's pose farther than this ([m], [rad]) is rejected (kiss-icp's pose is kept)."""


@dataclass(frozen=True)
class SlamState:
    """What SLAM knows after one scan: the hand-off to transports (see ``docs/slam.md``).

    Attributes:
        stamp: Simulation time of the scan [s] (stamp of the pose, of ``map -> odom`` and of the map).
        robot: The mapped robot.
        base_frame: The robot's root link (``base_link``).
        map_to_base: ``map_T_base_link``, the SLAM pose [m, rad]. The map frame is the robot's start pose.
        odom_to_base: ``odom_T_base_link`` from the wheel odometry at the scan's step.
        map_to_odom: ``map_T_odom = map_T_base @ inverse(odom_T_base)``: the ``map -> odom`` transform for /tf.
        grid: The occupancy grid (live object: ``grid.data()`` is the int8 ``OccupancyGrid.data``).
        registered: Whether this scan was registered (False: too few points, the pose followed the odometry).
    """

    stamp: float
    robot: str
    base_frame: str
    map_to_base: Pose2
    odom_to_base: Pose2
    map_to_odom: Pose2
    grid: OccupancyGrid
    registered: bool


class SlamFeature(Feature):
    """SLAM for one robot: ``<plugin name="slam" agent="robot_000" voxel_size="0.2" resolution="0.05"/>``.

    Each scan of the robot's lidar is turned into points in ``base_link`` (beams beyond range or below
    ``range_min`` dropped), registered with kiss-icp (started from the wheel odometry's motion), refined
    point-to-line (:mod:`.linemap`), and traced into a log-odds occupancy grid. The map frame is the robot's start
    pose (the wheel odometry's origin), anchored by one extra scan at the first step (see ``docs/slam.md``).
    The work runs in a step observer right after the scan's step, once the wheel odometry of that step is
    integrated, so ``map -> odom`` pairs a SLAM pose and an odometry pose of the same instant.

    Attributes:
        robot: The mapped robot.
        latest: The state after the latest scan (``None`` before the first).
        pose_history: ``(stamp [s], map_T_base)`` for every processed scan.
        scan_times: Wall-clock processing time of every scan [s].
        scan_cpu_times: CPU time of this thread for every scan [s] (the cost without other processes' share).
        grid: The occupancy grid.
        base_to_lidar: The static ``base_link -> lidar link`` transform projected on the ground plane.
    """

    name: ClassVar[str] = "slam"
    config_model: ClassVar[type[SlamConfig]] = SlamConfig

    @classmethod
    def api_entries(cls) -> list[ApiEntry]:
        """``<robot>_save_map`` (sigcore_msgs/srv/SaveMap)."""
        return api.entries()

    def __init__(self, sim: Simulation, config: SlamConfig) -> None:
        cfg = config
        robots = [a.name for a in sim.world.agents if isinstance(a, Robot)]
        if cfg.agent not in robots:
            raise FieldError("agent", f"'{cfg.agent}' is not a robot of this world; robots: "
                                      f"{', '.join(robots) or 'none'}")
        model = sim.entities.robot_model(cfg.agent)
        if model.drive is None:
            raise FieldError("agent", f"robot '{cfg.agent}' has no <drive>; SLAM needs its wheel odometry")
        lidars = [lidar.name for lidar in model.lidars]
        name = cfg.lidar or (lidars[0] if lidars else "")
        if name not in lidars:
            raise FieldError("lidar" if cfg.lidar else "agent",
                             f"robot '{cfg.agent}' has no lidar '{name}'; lidars: "
                             f"{', '.join(lidars) or 'none (add a <lidar> to the robot)'}")
        self.config = cfg
        self.robot = cfg.agent
        self.lidar = name
        self.sensor: LidarSensor = next(s for s in sim.entities.lidars
                                        if s.robot == self.robot and s.model.name == name)
        self.base_frame = sim.entities.urdf(self.robot).root
        self.base_to_lidar = _relative_pose(sim, self.robot, self.sensor.model.link)
        angles = self.sensor.angle_min + self.sensor.increment * np.arange(self.sensor.model.beams)
        self._directions = np.stack([np.cos(angles + self.base_to_lidar.yaw),
                                     np.sin(angles + self.base_to_lidar.yaw)], axis=1)
        self._odometry = sim.entities.enable_odometry(self.robot, cfg.odometry_noise)
        self._matcher = ScanMatcher(cfg.voxel_size, cfg.max_points_per_voxel, 0.0, self.sensor.model.range[1] + 1.0)
        width = math.ceil(cfg.size[0] / cfg.resolution - 1e-9)
        height = math.ceil(cfg.size[1] / cfg.resolution - 1e-9)
        origin = cfg.origin or (-width * cfg.resolution / 2, -height * cfg.resolution / 2)
        self.grid = OccupancyGrid(width, height, cfg.resolution, origin, cfg.hit, cfg.miss, cfg.clamp)
        self._lines = LineMap(math.ceil(width * cfg.resolution / cfg.voxel_size),
                              math.ceil(height * cfg.resolution / cfg.voxel_size), cfg.voxel_size,
                              origin) if cfg.refine else None
        self._anchor = LidarSensor(self.robot, self.sensor.model, sim.dt, sim.world.seed + 104_729)
        self.latest: SlamState | None = None
        self.pose_history: list[tuple[float, Pose2]] = []
        self.scan_times: list[float] = []
        self.scan_cpu_times: list[float] = []
        self._start: Pose2 | None = None
        self._last_odom: Pose2 | None = None
        self._pending: Scan | None = None
        self._declare(sim)
        sim.events.subscribe("scan", self._on_scan)
        sim.events.subscribe("step", self._on_step)

    def _declare(self, sim: Simulation) -> None:
        """The publications (``/map``, ``/<robot>/slam_pose``, ``map -> odom`` on ``/tf``) and the static
        ``world -> map`` (the robot's start pose), which replaces ``world -> odom`` in the core's tree."""
        self.map_frame = sim.frames.name(self.robot, "map")
        self.odom_frame = sim.frames.name(self.robot, "odom")
        x, y, yaw = self._odometry.origin
        sim.frames.remove_static(self.odom_frame)
        sim.frames.set_static(WORLD, self.map_frame, (x, y, 0.0), planar_quaternion(yaw))
        declare = sim.publications.declare
        self._map_pub = declare(Publication("/map", "nav_msgs/msg/OccupancyGrid", "latched",
                                            f"the occupancy grid, when it changed, at most {MAP_RATE:g} Hz", "slam"))
        self._pose_pub = declare(Publication(f"/{self.robot}/slam_pose", "geometry_msgs/msg/PoseStamped", "state",
                                             "the SLAM pose in the map frame, after each scan", "slam"))
        self._tf_pub = declare(Publication("/tf", "tf2_msgs/msg/TFMessage", "tf", "map -> odom after each scan",
                                           "slam"))
        self._dt, self._dt_ns = sim.dt, round(sim.dt * 1e9)
        self._last_map_time = -math.inf
        self._last_updates = -1

    # ------------------------------------------------------------------ per scan
    def _on_scan(self, scan: Scan) -> None:
        if scan.robot == self.robot and scan.lidar == self.lidar:
            self._pending = scan

    def _on_step(self, sim: Simulation) -> None:
        if self._pending is not None:
            scan, self._pending = self._pending, None
            self._publish(self.process(scan, self._odometry.state))
        elif self._start is None:
            # anchor the map with a scan at the first step, before the robot has moved (the wheel odometry, which
            # defines the map frame at the first processed scan, may already have slipped by the first regular scan)
            self._publish(self.process(self._anchor.scan(sim.backend, sim.time), self._odometry.state))

    def _publish(self, state: SlamState) -> None:
        """``map -> odom`` and the pose stamped with the scan's step; the map when it changed, at most
        :data:`MAP_RATE` times per simulated second (latched, so it is kept for sinks that connect later)."""
        if not self._tf_pub.active:
            return
        stamp = round(state.stamp / self._dt) * self._dt_ns
        m2o, pose = state.map_to_odom, state.map_to_base
        self._tf_pub.publish({"transforms": [transform_fields(self.map_frame, self.odom_frame, stamp,
                                                              (m2o.x, m2o.y, 0.0), planar_quaternion(m2o.yaw))]},
                             stamp)
        w, _, _, z = planar_quaternion(pose.yaw)
        self._pose_pub.publish({"header": {"stamp": stamp, "frame_id": self.map_frame},
                                "pose": {"position": {"x": pose.x, "y": pose.y, "z": 0.0},
                                         "orientation": {"x": 0.0, "y": 0.0, "z": z, "w": w}}}, stamp)
        grid = state.grid
        if grid.updates != self._last_updates and state.stamp - self._last_map_time >= 1.0 / MAP_RATE - 1e-9:
            self._last_updates, self._last_map_time = grid.updates, state.stamp
            self._map_pub.publish(self.occupancy_grid_fields(stamp), stamp)

    def occupancy_grid_fields(self, stamp_ns: int) -> dict[str, Any]:
        """The ``nav_msgs/OccupancyGrid`` fields of the grid (row-major from the origin cell, -1 unknown)."""
        grid = self.grid
        ox, oy = grid.origin
        return {"header": {"stamp": stamp_ns, "frame_id": self.map_frame},
                "info": {"map_load_time": stamp_ns, "resolution": float(grid.resolution), "width": int(grid.width),
                         "height": int(grid.height),
                         "origin": {"position": {"x": float(ox), "y": float(oy), "z": 0.0},
                                    "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}},
                "data": grid.data().ravel()}

    def process(self, scan: Scan, odometry: OdometryState) -> SlamState:
        """Register one scan and update the grid (called by the simulation; public for replaying logs).

        Args:
            scan: A scan of the mapped lidar.
            odometry: The wheel odometry at the scan's time.
        """
        t0, c0 = time.perf_counter(), time.thread_time()
        ranges = scan.ranges
        hit = np.isfinite(ranges) & (ranges >= scan.range_min)
        use = hit | np.isinf(ranges)
        hit_used = hit[use]
        reach = np.where(hit, ranges, scan.range_max)[use]
        lidar = self.base_to_lidar
        ends = self._directions[use] * reach[:, None]
        ends[:, 0] += lidar.x
        ends[:, 1] += lidar.y
        odom = Pose2(odometry.x, odometry.y, odometry.yaw)
        if self._start is None:
            self._start = odom  # the first (anchor) scan, at the first step: the odometry's origin, the start pose
        motion = None
        if self.config.odometry_guess and self._last_odom is not None:
            motion = self._last_odom.inverse() @ odom
        points = ends[hit_used]
        registered = len(points) >= MIN_POINTS
        if registered:
            local = self._matcher.register(points, motion)
        else:
            local = self._matcher.pose @ motion if motion is not None else self._matcher.pose
            self._matcher.reset_pose(local)
        pose = self._start @ local
        if self._lines is not None:
            if registered and self.pose_history:
                every = max(1, round(len(points) / REFINE_POINTS))
                refined, used = self._lines.align(pose, points[::every])
                if used >= MIN_POINTS // every and _close(refined, pose):
                    pose = refined
                    self._matcher.correct(self._start.inverse() @ pose)
        map_ends = pose.apply(ends)
        if self._lines is not None:
            self._lines.add(map_ends[hit_used])
        sensor = pose @ lidar
        self.grid.integrate((sensor.x, sensor.y), map_ends, hit_used)
        self._last_odom = odom
        state = SlamState(scan.stamp, self.robot, self.base_frame, pose, odom, pose @ odom.inverse(), self.grid,
                          registered)
        self.latest = state
        self.pose_history.append((scan.stamp, pose))
        self.scan_times.append(time.perf_counter() - t0)
        self.scan_cpu_times.append(time.thread_time() - c0)
        return state

    def reset(self) -> None:
        """After a simulation reset the robot is back at its start, the map's origin: keep the map, put the pose
        back there, and start the next registration from it."""
        self._pending = None
        self._last_odom = None
        if self._start is not None:
            self._matcher.relocate(self._start.inverse())

    # ------------------------------------------------------------------ outputs
    def save_map(self, path: str | Path) -> Path:
        """Write the grid as ``<path>.pgm`` + ``<path>.yaml`` (map_server format); returns the YAML path.

        Raises:
            OSError: the files cannot be written.
        """
        return save_map(path, self.grid.data(), self.grid.resolution, self.grid.origin)

    def summary(self) -> dict[str, Any]:
        """Scans processed, per-scan time [ms] (median and maximum) and the final SLAM pose."""
        if not self.scan_times:
            return {"scans": 0}
        ms = np.asarray(self.scan_times) * 1e3
        pose = self.pose_history[-1][1]
        return {"scans": len(ms), "scan_ms_median": round(float(np.median(ms)), 3),
                "scan_ms_max": round(float(ms.max()), 3),
                "pose": [round(pose.x, 4), round(pose.y, 4), round(pose.yaw, 4)]}


def _close(a: Pose2, b: Pose2) -> bool:
    d = a.inverse() @ b
    return math.hypot(d.x, d.y) <= MAX_CORRECTION[0] and abs(d.yaw) <= MAX_CORRECTION[1]


def _relative_pose(sim: Simulation, robot: str, link: str) -> Pose2:
    """``base_T_link`` on the ground plane, from the backend's current link poses."""
    base_pos, base_quat = sim.backend.get_pose(robot)
    link_pos, link_quat = sim.backend.get_pose(robot, link)
    rel = quat_to_matrix(base_quat).T @ (np.asarray(link_pos) - np.asarray(base_pos))
    return Pose2(float(rel[0]), float(rel[1]), quat_yaw(link_quat) - quat_yaw(base_quat))
