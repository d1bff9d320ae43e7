"""The ROS 2 side of the publication contract: endpoints from declarations, message filling, the endpoint list."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from rosdomains import next_domain

pytest.importorskip("rclpy")
pytest.importorskip("sigcore_msgs")

from nav_msgs.msg import OccupancyGrid  # noqa: E402
from sensor_msgs.msg import LaserScan  # noqa: E402
from sigcore_ros2.publications import fill_message  # noqa: E402
from sigcore_ros2.transport import Ros2Transport  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

from sigcore.publish import transform_fields  # noqa: E402
from sigcore.sim import Simulation  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

pytestmark = pytest.mark.ros2

ROOT = Path(__file__).parent.parent.parent


def test_fill_message_sets_nested_fields_sequences_and_exact_stamps() -> None:
    """Nested dictionaries, message sequences, numeric arrays and int-nanosecond stamps land exactly."""
    tf = fill_message(TFMessage(), {"transforms": [transform_fields("world", "odom", 3_000_000_001, (1, 2, 3),
                                                                    (1, 0, 0, 0))]})
    t = tf.transforms[0]
    assert (t.header.stamp.sec, t.header.stamp.nanosec, t.header.frame_id, t.child_frame_id) == (
        3, 1, "world", "odom")
    assert (t.transform.translation.x, t.transform.translation.z, t.transform.rotation.w) == (1.0, 3.0, 1.0)
    grid = fill_message(OccupancyGrid(), {"info": {"width": 3, "resolution": 0.05},
                                          "data": np.array([-1, 0, 100], dtype=np.int8)})
    assert list(grid.data) == [-1, 0, 100] and grid.info.width == 3
    scan = fill_message(LaserScan(), {"header": {"stamp": 0.5}, "ranges": np.array([1.0, np.inf])})
    assert scan.header.stamp.nanosec == 500_000_000 and list(scan.ranges) == [1.0, float("inf")]
    with pytest.raises(KeyError, match="no field 'rangez'.*ranges"):
        fill_message(LaserScan(), {"rangez": []})


def test_describe_lists_exactly_the_endpoints_start_creates(monkeypatch: pytest.MonkeyPatch) -> None:
    """Ros2Transport.describe (what `sigcore api` prints) equals the endpoints a started transport has."""
    monkeypatch.setenv("ROS_DOMAIN_ID", str(next_domain()))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    sim = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")
    transport = Ros2Transport()
    planned = transport.describe(sim)
    transport.start(sim)
    try:
        assert transport.endpoints == planned
    finally:
        transport.stop()
    assert {"/referee/score", "/referee/events", "/referee/result", "/tf_static", "robot_000_ik_solve",
            "robot_000_scan", "/simulate_steps"} <= set(planned)


def test_sigcore_api_lists_every_endpoint_unwrapped() -> None:
    """`sigcore api WORLD | cat` names the features' endpoints, the referee topics and simulation_interfaces,
    with no line cut at 80 columns."""
    r = subprocess.run([sys.executable, "-m", "sigcore", "api", str(ROOT / "worlds" / "cleanup.xml"), "--all"],
                       capture_output=True, text=True, timeout=120, env={**os.environ, "COLUMNS": "80"})
    assert r.returncode == 0, r.stderr
    names = {line.split()[0] for line in r.stdout.splitlines() if line.startswith("  ")}
    assert {"_ik_solve", "robot_000_ik", "robot_000_ik_solve", "/referee/score", "/referee/events",
            "/referee/result", "/get_simulator_features", "/robot_000/cmd_vel", "robot_000_scan"} <= names
    assert any(len(line) > 100 for line in r.stdout.splitlines())
    total = r.stdout.strip().splitlines()[-1]
    assert total.endswith("in all") and int(total.split(", ")[-1].split()[0]) > 200
