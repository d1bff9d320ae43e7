"""The slam feature: accuracy on a short route, the occupancy grid, the hand-off, config errors, zero cost off."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from sigcore_slam import Pose2, SlamFeature
from slam_room import PLUGIN_LINE, ROBOT, drive_to, ground_truth, room_world

from sigcore import plugins
from sigcore.sim import Simulation
from sigcore.world import WorldError

ROUTE = [(0.0, -0.8), (2.2, -0.8), (2.2, 0.0), (0.6, 0.0), (-1.2, 0.9), (-1.2, -0.8), (0.0, 0.0)]


def _slam(sim: Simulation) -> SlamFeature:
    feature = sim.features["slam"]
    assert isinstance(feature, SlamFeature)
    return feature


def _cell(feature: SlamFeature, x: float, y: float) -> int:
    """Occupancy (-1, 0..100) of the cell holding map point (x, y)."""
    grid = feature.grid
    col = int(math.floor((x - grid.origin[0]) / grid.resolution))
    row = int(math.floor((y - grid.origin[1]) / grid.resolution))
    return int(grid.data()[row, col])


def test_registered_as_the_slam_feature() -> None:
    """The entry point registers SlamFeature under the name 'slam'."""
    assert plugins.get_feature("slam") is SlamFeature


@pytest.mark.slow
def test_ate_on_a_short_route_below_1cm(room_sim: Simulation) -> None:
    """Driving 10 m with turns in place, the SLAM position RMSE against ground truth stays below 1 cm (2.4 mm)."""
    slam = _slam(room_sim)
    truth: list[tuple[float, float]] = []

    def record(sim: Simulation) -> None:
        while len(truth) < len(slam.pose_history):
            x, y, _ = ground_truth(sim)
            truth.append((x, y))  # the robot starts at the world origin facing +x: map = world here

    room_sim.events.subscribe("step", record)
    drive_to(room_sim, ROUTE)
    est = np.array([(p.x, p.y) for _, p in slam.pose_history])
    ref = np.array(truth)
    assert len(est) > 200  # scans were processed all along
    err = np.hypot(*(est - ref).T)
    assert math.sqrt(float(np.mean(err**2))) < 0.01
    assert err[-1] < 0.01
    # the wheel odometry alone drifts more than SLAM (the test would pass trivially with perfect odometry)
    odo = room_sim.entities.odometry[ROBOT].state
    assert math.hypot(odo.x - ref[-1, 0], odo.y - ref[-1, 1]) > err[-1]


def test_hand_off_frames_are_consistent(room_sim: Simulation) -> None:
    """latest: map->odom composed with odom->base_link is the SLAM pose, stamped with the scan's time."""
    drive_to(room_sim, ROUTE[:2])
    slam = _slam(room_sim)
    state = slam.latest
    assert state is not None
    composed = state.map_to_odom @ state.odom_to_base
    assert composed.x == pytest.approx(state.map_to_base.x, abs=1e-9)
    assert composed.y == pytest.approx(state.map_to_base.y, abs=1e-9)
    assert composed.yaw == pytest.approx(state.map_to_base.yaw, abs=1e-9)
    assert state.stamp == pytest.approx(slam.pose_history[-1][0])
    assert state.stamp == pytest.approx(math.floor(room_sim.time * 10 + 1e-6) / 10)  # the last 10 Hz scan
    assert (state.robot, state.base_frame) == (ROBOT, "base_link")
    odo = room_sim.entities.odometry[ROBOT].state
    assert state.odom_to_base.x == pytest.approx(odo.x, abs=1e-3)


def test_grid_marks_walls_occupied_and_the_inside_free(room_sim: Simulation) -> None:
    """After a short drive, cells on the walls' faces are occupied, the floor inside is free, outside unknown."""
    drive_to(room_sim, ROUTE[:3])
    slam = _slam(room_sim)
    data = slam.grid.data()
    assert data.dtype == np.int8 and data.min() >= -1 and data.max() <= 100
    walls = [(3.01, y) for y in np.linspace(-1.2, 1.2, 9)] + [(x, 1.51) for x in np.linspace(-1.8, 2.8, 9)] + \
            [(x, -1.51) for x in np.linspace(-1.8, 2.8, 9)] + [(-2.01, y) for y in np.linspace(-1.2, 1.2, 9)]
    occupied = [_cell(slam, x, y) for x, y in walls]
    assert sum(v >= 65 for v in occupied) >= 0.9 * len(walls), occupied
    inside = [(x, y) for x in np.linspace(-1.6, 2.6, 8) for y in np.linspace(-1.1, 1.1, 5)
              if not (1.2 < x < 1.8 and 0.5 < y < 1.1)]
    free = [_cell(slam, x, y) for x, y in inside]
    assert all(0 <= v <= 20 for v in free), free
    assert _cell(slam, 1.5, 0.66) >= 65  # the pillar's south face
    assert _cell(slam, 4.0, 0.0) == -1 and _cell(slam, 0.0, 2.5) == -1


def test_scans_without_returns_keep_the_pose(room_sim: Simulation) -> None:
    """A scan with every beam out of range is not registered: the pose follows the odometry, nothing breaks."""
    room_sim.step(100)
    slam = _slam(room_sim)
    before = slam.latest
    assert before is not None
    scan = room_sim.entities.lidars[0].last
    assert scan is not None
    empty = type(scan)(**{**scan.__dict__, "ranges": np.full_like(scan.ranges, np.inf), "stamp": scan.stamp + 0.1})
    state = slam.process(empty, room_sim.entities.odometry[ROBOT].state)
    assert not state.registered
    assert math.hypot(state.map_to_base.x - before.map_to_base.x, state.map_to_base.y - before.map_to_base.y) < 0.01


@pytest.mark.parametrize(("attributes", "column", "expected"), [
    ('agent="robot_000" voxel_size="-0.2"', 41, "attribute 'voxel_size': '-0.2' is out of range; valid: 0 < "
                                                "voxel_size <= 5 [m]"),
    ('agent="robot_000" resolution="fine"', 41, "attribute 'resolution': 'fine' is not a number"),
    ('agent="robot_000" size="10"', 41, "attribute 'size': expected two numbers 'a b', got '10'"),
    ('agent="robot_000" size="2000 2000"', 41, "attribute 'size': size '2000 2000' at resolution 0.05 is"),
    ('agent="robot_000" odometry_guess="maybe"', 41, "attribute 'odometry_guess': 'maybe' is not a boolean"),
    ('agent="robot_000" voxel="0.2"', 41, "unknown attribute of plugin 'slam' (did you mean 'voxel_size'?); "
                                          "valid: name, agent, lidar, voxel_size"),
    ('agent="nobody"', 23, "attribute 'agent': 'nobody' is not a robot of this world; robots: robot_000"),
    ('agent="robot_000" lidar="front"', 41, "attribute 'lidar': robot 'robot_000' has no lidar 'front'; "
                                            "lidars: base_scan"),
    ('voxel_size="0.2"', 3, "<plugin>: required attribute 'agent' is missing"),
])
def test_invalid_config_is_a_world_error(attributes: str, column: int, expected: str) -> None:
    """Each bad attribute is reported at its line:column in a WorldError that names it and what is valid."""
    with pytest.raises(WorldError) as info:
        Simulation(room_world(f'  <plugin name="slam" {attributes}/>\n'), "mujoco")
    assert f"box_room.xml:8:{column}: " in str(info.value)  # the <plugin> line, the attribute's column
    assert expected in str(info.value)


def test_world_without_the_plugin_pays_nothing() -> None:
    """Without <plugin name="slam">, the simulation has no scan or step observer and no odometry."""
    sim = Simulation(room_world(None), "mujoco")
    sim.step(100)
    assert "slam" not in sim.features
    assert not sim.events.subscriptions("scan") and not sim.events.subscriptions("step")
    assert sim.entities.odometry == {}
    with_slam = Simulation(room_world(PLUGIN_LINE), "mujoco")
    assert len(with_slam.events.subscriptions("scan")) == 1 and len(with_slam.events.subscriptions("step")) == 1


@pytest.mark.slow
def test_loading_plugins_does_not_import_kiss_icp() -> None:
    """Discovering the plugin (what every sigcore run does) imports neither kiss-icp nor the feature's work."""
    code = ("import sys; from sigcore import plugins; assert plugins.get_feature('slam').name == 'slam'; "
            "print('kiss_icp' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"


def test_pose2_composition_and_inverse() -> None:
    """Pose2: a @ inverse(a) is the identity and apply() agrees with composition."""
    a, b = Pose2(1.0, -2.0, 2.5), Pose2(0.3, 0.4, -1.0)
    ident = a @ a.inverse()
    assert (ident.x, ident.y, ident.yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    point = (a @ b).apply(np.array([[0.5, -0.25]]))
    assert point == pytest.approx(a.apply(b.apply(np.array([[0.5, -0.25]]))), abs=1e-12)


def test_reset_puts_the_pose_back_at_the_start(room_sim: Simulation) -> None:
    """After driving and a simulation reset, SLAM's pose is back at the start and tracks the next moves."""
    drive_to(room_sim, ROUTE[:2])
    room_sim.reset()
    drive_to(room_sim, [(0.8, 0.0)])
    slam = _slam(room_sim)
    state = slam.latest
    assert state is not None
    x, y, _ = ground_truth(room_sim)
    assert math.hypot(state.map_to_base.x - x, state.map_to_base.y - y) < 0.02
