"""SLAM accuracy and cost: robot_000 drives two loops of the clean-up room with the ``slam`` feature on.

Usage: .venv/bin/python bench/slam_accuracy.py [--loops N] [--speed V] [--no-refine] [--open-loop]
           [--odometry-noise F] [--grid-offset D] [--save-map BASE] [--smoke]
       --smoke: one loop (--loops 1), to check that the bench runs and prints every figure (tests/bench).

The world is ``worlds/cleanup.xml`` with ``<plugin name="slam" agent="robot_000" .../>`` added to its ``<world>``
element in memory (the file itself does not enable SLAM); the bench stops with a message if the simulation was built
without the ``slam`` feature. A waypoint follower drives the robot on the ground truth around a rectangle that keeps
at least 0.35 m from every piece of furniture: (-4, -1) -> (2.8, -1) -> (2.8, 1) -> (-4, 1) -> (-4, -1), ``--loops``
times (turning in place at the corners, 0.5 m/s on the straights), then it stops.

Figures:

* ATE: RMSE of the SLAM position of ``base_link`` against the simulator's (the backend's pose of ``base_link``),
  both in the map frame (the robot's start pose), at every processed scan; no alignment is fitted. Also the
  yaw RMSE and the final drift (position error at the last scan), next to the wheel odometry's.
* Per-scan processing time (wall clock inside the feature: points, kiss-icp, refinement, grid), median and p99,
  and the number of scans over the scan period (100 ms at 10 Hz: falling behind); the same as the thread's CPU
  time, which a busy shared machine inflates less; the real-time factor of the whole run (physics, lidar, SLAM,
  the follower).
* Map IoU: a ground-truth grid rasterised on the SLAM grid's cells from the horizontal cross-section, at the
  lidar's height, of every collision geom except the robot's (boxes, cylinders, spheres, capsules: 5 x 5 samples
  per cell, occupied if any sample is inside). Only geometry spanning the lidar's height +- 2 cm counts: the robot
  stands 0.5 deg tilted on its back caster, so the scan plane's height drifts by about 1.7 cm per 2 m of range,
  and a 2 cm thick shelf at exactly the lidar's height (the wagon's lower shelf, z 0.24-0.26) is passed over at
  most distances. IoU = |S and G| / |S or G| over the cells SLAM observed (known), S = SLAM cells >= 65 (the
  map_saver's occupied threshold), G = ground-truth occupied; also with one cell of tolerance (a cell counts as
  matched if the other grid has an occupied cell within one cell).
  The faces of the world's geometry lie on multiples of 5 cm. By default the SLAM grid is offset by half a cell
  (``--grid-offset 0.025``) so that faces do not coincide with cell boundaries, where float rounding alone decides
  which of two cells a face's hits fall in; ``--grid-offset 0`` shows that case.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import mujoco
import numpy as np
import numpy.typing as npt
from lxml import etree
from sigcore_slam import Pose2, SlamFeature

from sigcore.geometry import quat_yaw
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parent.parent
WORLD = ROOT / "worlds" / "cleanup.xml"
ROBOT = "robot_000"
ROUTE = [(-4.0, -1.0), (2.8, -1.0), (2.8, 1.0), (-4.0, 1.0)]

Array = npt.NDArray[np.float64]
BAND = 0.02
"""Ground truth counts geometry that spans the lidar's height +- this [m] (see the module docstring)."""


def make_sim(plugin_attributes: dict[str, str]) -> Simulation:
    """The clean-up world with ``<plugin name="slam" agent="robot_000" .../>`` added in memory as the first child of
    its ``<world>`` element (whatever that element's attributes).

    Raises:
        SystemExit: the world has no ``<world>`` root, or the simulation was built without the ``slam`` feature.
    """
    text = WORLD.read_text()
    root = etree.fromstring(text.encode("utf-8"), parser=etree.XMLParser(resolve_entities=False))
    if root.tag != "world":
        raise SystemExit(f"{WORLD}: the root element is <{root.tag}>, not <world>: the slam plugin cannot be added")
    root.insert(0, etree.Element("plugin", {"name": "slam", "agent": ROBOT, **plugin_attributes}))
    sim = Simulation(parse_world(WORLD, etree.tostring(root, encoding="unicode")), "mujoco")
    if "slam" not in sim.features:
        raise SystemExit(f"{WORLD} was built without the slam feature (features: {', '.join(sim.features) or 'none'})"
                         ": the <plugin name=\"slam\"> added in memory did not get into the world")
    return sim


def ground_truth(sim: Simulation) -> Pose2:
    """World pose of base_link on the ground plane."""
    pos, quat = sim.backend.get_pose(ROBOT)
    return Pose2(float(pos[0]), float(pos[1]), quat_yaw(quat))


def drive(sim: Simulation, slam: SlamFeature, loops: int, speed: float) -> tuple[list[Pose2], float]:
    """Follow the route on ground truth; returns the map-frame ground truth at every processed scan and the
    wall time [s]."""
    robot = sim.robot(ROBOT)
    start_inv = ground_truth(sim).inverse()
    truth: list[Pose2] = []

    def record(s: Simulation) -> None:
        while len(truth) < len(slam.pose_history):
            truth.append(start_inv @ ground_truth(s))

    sim.events.subscribe("step", record)
    waypoints = ROUTE[:] * loops + [ROUTE[0]]
    steps_per_control = 10  # 50 Hz
    t0 = time.perf_counter()
    for wx, wy in waypoints:
        for _ in range(200_000):
            pose = ground_truth(sim)
            dx, dy = wx - pose.x, wy - pose.y
            dist = math.hypot(dx, dy)
            if dist < 0.05:
                break
            err = math.atan2(math.sin(math.atan2(dy, dx) - pose.yaw), math.cos(math.atan2(dy, dx) - pose.yaw))
            if abs(err) > 0.25:
                robot.set_base_velocity(0.0, max(-1.0, min(1.0, 2.0 * err)))
            else:
                robot.set_base_velocity(min(speed, 1.5 * dist + 0.05), 2.0 * err)
            sim.step(steps_per_control)
    robot.set_base_velocity(0.0, 0.0)
    sim.step(500)
    return truth, time.perf_counter() - t0


# ---------------------------------------------------------------------------------------------- ground-truth grid
def _inside(geom_type: int, size: Array, local: Array) -> npt.NDArray[np.bool_]:
    """Whether (n, 3) geom-frame points are inside a MuJoCo primitive."""
    x, y, z = local[:, 0], local[:, 1], local[:, 2]
    if geom_type == mujoco.mjtGeom.mjGEOM_BOX:
        return (np.abs(x) <= size[0]) & (np.abs(y) <= size[1]) & (np.abs(z) <= size[2])
    if geom_type == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return (x * x + y * y <= size[0] ** 2) & (np.abs(z) <= size[1])
    if geom_type == mujoco.mjtGeom.mjGEOM_SPHERE:
        return x * x + y * y + z * z <= size[0] ** 2
    if geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE:
        zc = np.clip(z, -size[1], size[1])
        return x * x + y * y + (z - zc) ** 2 <= size[0] ** 2
    if geom_type == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return (x / size[0]) ** 2 + (y / size[1]) ** 2 + (z / size[2]) ** 2 <= 1.0
    raise ValueError(f"geom type {geom_type} is not rasterised (boxes, cylinders, spheres, capsules, ellipsoids)")


def truth_grid(sim: Simulation, slam: SlamFeature, start: Pose2, height: float) -> npt.NDArray[np.bool_]:
    """(height, width) ground-truth occupancy on the SLAM grid's cells (see the module docstring)."""
    model, data = sim.backend.model, sim.backend.data  # type: ignore[attr-defined]
    grid = slam.grid
    sub = (np.arange(5) + 0.5) / 5 * grid.resolution  # 5 x 5 samples per cell
    occupied = np.zeros((grid.height, grid.width), bool)
    for g in range(model.ngeom):
        body = model.body(model.geom_bodyid[g]).name
        if model.geom_group[g] != 0 or model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE or body.startswith(
                f"{ROBOT}/"):
            continue
        centre, rot, radius = data.geom_xpos[g], data.geom_xmat[g].reshape(3, 3), model.geom_rbound[g]
        if abs(centre[2] - height) > radius + BAND:
            continue
        # map-frame bounding box of the geom -> candidate cells
        c = start.inverse().apply(centre[None, :2])[0]
        col0 = max(0, int((c[0] - radius - grid.origin[0]) / grid.resolution) - 1)
        col1 = min(grid.width, int((c[0] + radius - grid.origin[0]) / grid.resolution) + 2)
        row0 = max(0, int((c[1] - radius - grid.origin[1]) / grid.resolution) - 1)
        row1 = min(grid.height, int((c[1] + radius - grid.origin[1]) / grid.resolution) + 2)
        if col0 >= col1 or row0 >= row1:
            continue
        xs = grid.origin[0] + np.arange(col0, col1)[:, None] * grid.resolution + sub[None, :]
        ys = grid.origin[1] + np.arange(row0, row1)[:, None] * grid.resolution + sub[None, :]
        # every sample of every candidate cell, as (rows, cols, 5, 5) -> world frame
        mx = np.broadcast_to(xs[None, :, None, :], (row1 - row0, col1 - col0, 5, 5)).reshape(-1)
        my = np.broadcast_to(ys[:, None, :, None], (row1 - row0, col1 - col0, 5, 5)).reshape(-1)
        world_xy = start.apply(np.stack([mx, my], axis=1))
        inside = np.ones(len(mx), bool)
        for z in (height - BAND, height + BAND):  # inside at both ends: inside across the band (convex geoms)
            local = (np.column_stack([world_xy, np.full(len(mx), z)]) - centre) @ rot
            inside &= _inside(int(model.geom_type[g]), model.geom_size[g], local)
        occupied[row0:row1, col0:col1] |= inside.reshape(row1 - row0, col1 - col0, 25).any(axis=2)
    return occupied


def iou(slam_occ: npt.NDArray[np.bool_], truth: npt.NDArray[np.bool_], observed: npt.NDArray[np.bool_],
        tolerance: int = 0) -> float:
    """IoU over observed cells; with ``tolerance`` k, a cell counts as matched if the other grid has an occupied
    cell within k cells (Chebyshev)."""
    s, g = slam_occ & observed, truth & observed
    if tolerance == 0:
        return float((s & g).sum() / max(1, (s | g).sum()))
    gd, sd = _dilate(g, tolerance), _dilate(s, tolerance)
    matched_s = (s & gd).sum()
    matched_g = (g & sd).sum()
    unmatched = (s & ~gd).sum() + (g & ~sd).sum()
    matched = (matched_s + matched_g) / 2
    return float(matched / max(1.0, matched + unmatched))


def _dilate(a: npt.NDArray[np.bool_], k: int) -> npt.NDArray[np.bool_]:
    out = a.copy()
    for dr in range(-k, k + 1):
        for dc in range(-k, k + 1):
            out |= np.roll(np.roll(a, dr, axis=0), dc, axis=1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--loops", type=int, default=2)
    ap.add_argument("--speed", type=float, default=0.5, help="cruise speed [m/s]")
    ap.add_argument("--voxel-size", type=float, default=0.2)
    ap.add_argument("--resolution", type=float, default=0.05)
    ap.add_argument("--odometry-noise", type=float, default=0.0, help="wheel-speed noise [fraction]")
    ap.add_argument("--open-loop", action="store_true", help="constant-velocity ICP guess instead of odometry")
    ap.add_argument("--no-refine", action="store_true", help="kiss-icp alone (no point-to-line refinement)")
    ap.add_argument("--grid-offset", type=float, default=None,
                    help="shift of the grid's cell boundaries [m] (default: half a cell)")
    ap.add_argument("--save-map", default="", help="write the map as BASE.pgm + BASE.yaml")
    ap.add_argument("--smoke", action="store_true", help="one loop: a check that the bench runs, not a measurement")
    args = ap.parse_args()
    if args.smoke:
        args.loops = 1

    offset = args.resolution / 2 if args.grid_offset is None else args.grid_offset
    size = 30.0
    attrs = {"voxel_size": str(args.voxel_size), "resolution": str(args.resolution), "size": f"{size} {size}",
             "origin": f"{-size / 2 - offset} {-size / 2 - offset}", "odometry_noise": str(args.odometry_noise),
             "odometry_guess": "false" if args.open_loop else "true", "refine": "false" if args.no_refine else "true"}
    sim = make_sim(attrs)
    slam = sim.features["slam"]
    assert isinstance(slam, SlamFeature)
    start = ground_truth(sim)
    height = float(sim.backend.get_pose(ROBOT, slam.sensor.model.link)[0][2])
    truth, wall = drive(sim, slam, args.loops, args.speed)

    est = np.array([[p.x, p.y, p.yaw] for _, p in slam.pose_history])
    ref = np.array([[p.x, p.y, p.yaw] for p in truth])
    err = est[:, :2] - ref[:, :2]
    dyaw = np.arctan2(np.sin(est[:, 2] - ref[:, 2]), np.cos(est[:, 2] - ref[:, 2]))
    length = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    odo = sim.entities.odometry[ROBOT].state
    odo_err = math.hypot(odo.x - ref[-1, 0], odo.y - ref[-1, 1])
    ms = np.asarray(slam.scan_times) * 1e3
    cpu = np.asarray(slam.scan_cpu_times) * 1e3
    period_ms = 1e3 / slam.sensor.model.rate

    truth_occ = truth_grid(sim, slam, start, height)
    data = slam.grid.data()
    observed = data >= 0
    slam_occ = data >= 65
    figures = {
        "route": f"{args.loops} loops, {length:.1f} m, {sim.time:.1f} s simulated, {len(est)} scans",
        "ATE RMSE [m]": f"{math.sqrt(float(np.mean(np.sum(err ** 2, axis=1)))):.4f}",
        "max position error [m]": f"{float(np.max(np.hypot(*err.T))):.4f}",
        "yaw RMSE [rad]": f"{math.sqrt(float(np.mean(dyaw ** 2))):.5f}",
        "final drift [m]": f"{float(np.hypot(*err[-1])):.4f} (wheel odometry alone: {odo_err:.4f})",
        "per-scan time [ms]": f"median {np.median(ms):.3f}, p99 {np.percentile(ms, 99):.3f}, max {ms.max():.3f}",
        "per-scan CPU time [ms]": f"median {np.median(cpu):.3f}, p99 {np.percentile(cpu, 99):.3f}, "
                                  f"max {cpu.max():.3f} (this thread only: without other processes' share)",
        f"scans over {period_ms:.0f} ms": f"{int((ms > period_ms).sum())}",
        "real-time factor": f"{sim.time / wall:.1f} (whole run: physics, lidar, SLAM, follower)",
        "configuration": " ".join(f'{k}="{v}"' for k, v in attrs.items()),
        "map IoU (occupied, observed cells)": f"{iou(slam_occ, truth_occ, observed):.3f}",
        "map IoU, 1-cell tolerance": f"{iou(slam_occ, truth_occ, observed, 1):.3f}",
        "cells occupied: SLAM / truth (observed)": f"{int((slam_occ & observed).sum())} / "
                                                    f"{int((truth_occ & observed).sum())}",
    }
    width = max(len(k) for k in figures)
    for key, value in figures.items():
        print(f"{key:<{width}}  {value}")
    if args.save_map:
        print(f"map written to {slam.save_map(args.save_map)}")


if __name__ == "__main__":
    main()
