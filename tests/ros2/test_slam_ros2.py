"""SLAM over ROS 2: /map, map -> odom on /tf, the SLAM pose and the REP-105 tree world -> map -> odom."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosproc import start_sim

pytestmark = pytest.mark.ros2

pytest.importorskip("sigcore_slam")

WORLD = Path(__file__).parent.parent / "slam" / "data" / "box_room.xml"


def test_slam_publishes_map_tf_and_pose(tmp_path: Path) -> None:
    """With <plugin name="slam">, /map (OccupancyGrid in 'map': unknown, free and occupied cells), map -> odom
    stamped at 10 Hz scan times, /robot_000/slam_pose, and world -> map (not world -> odom) on /tf_static are
    published."""
    sim = start_sim(tmp_path, WORLD, "--realtime")
    try:
        r = sim.client("slam.py", timeout=90)
    finally:
        sim.stop()
    assert r["maps"] >= 2 and r["map_frame"] == "map"
    assert r["map_info"] == [200, 200, pytest.approx(0.05)]
    values = set(r["map_values"])
    assert -1 in values and values <= set(range(-1, 101))  # unknown, then occupancy probabilities [%]
    assert min(values - {-1}) <= 20 and max(values) >= 65  # free space and walls are both seen
    assert ["world", "map"] in r["static_pairs"] and ["world", "odom"] not in r["static_pairs"]
    assert r["map_to_odom"] >= 5
    assert all(abs(s * 10 - round(s * 10)) < 1e-6 for s in r["m2o_stamps"])  # scan times: multiples of 0.1 s
    assert r["pose_frame"] == "map" and r["pose_x"] > 0.05
