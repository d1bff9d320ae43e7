"""examples/ros2/find_red_can.py, a plain rclpy node, against the clean-up world over ROS 2: it turns robot_000 until
the red can is in the middle of its head camera's image and reports the can's position in the camera's optical
frame from the colour and depth images and CameraInfo. The test checks that position against the ground truth: the
robot's pose from get_entity_state, the camera's pose on it (sigcore's own model of the world, in this process) and
can_0's world position."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import SimProcess, start_sim  # noqa: E402

from sigcore.geometry import quat_to_matrix  # noqa: E402
from sigcore.sim import Simulation  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

pytestmark = [pytest.mark.ros2, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
WORLD = ROOT / "worlds" / "cleanup.xml"
EXAMPLE = ROOT / "examples" / "ros2" / "find_red_can.py"
CAN = np.array([-1.8, 1.75, 0.761])
CAN_RADIUS = 0.033
TOLERANCE = 0.05
"""How far [m] the reported position may be from the can's axis at its centre's height: the camera sees the near
side of the can (its radius, 3.3 cm, nearer) and the red pixels' centre may be a pixel or two off."""
LATERAL = 0.1
"""How far [m] the reported position may be off sideways (x in the optical frame): the robot's pose is read after the
example stopped it, and the image it measured was taken while it still turned; under load (four test workers on 2
cores) the robot turned on by about 1 degree in between (5.1 cm at 2.8 m in one ci-fresh run). The depth and the
height (y, z) are not affected: :data:`TOLERANCE`."""


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SimProcess]:
    proc = start_sim(tmp_path_factory.mktemp("find_red_can"), WORLD)
    try:
        yield proc
    finally:
        proc.stop()


def test_the_example_finds_the_red_can_where_it_is(sim: SimProcess) -> None:
    r = subprocess.run([sys.executable, str(EXAMPLE), "--timeout", "90"], env=sim.env, capture_output=True,
                       text=True, timeout=150)
    assert r.returncode == 0, r.stdout + r.stderr
    found = json.loads(r.stdout.strip().splitlines()[-1])
    assert found["found"], r.stdout + r.stderr + sim.output()
    assert found["frame"] == "head_rgbd_optical_frame" and "red can at x=" in r.stdout
    pose = sim.client("entity_pose.py", "robot_000")
    model = Simulation(parse_world(WORLD), "mujoco")
    model.backend.set_pose("robot_000", np.array(pose["xyz"]), np.array(pose["wxyz"]))
    position, quaternion = model.cameras.find("robot_000", "head_rgbd").pose(model.backend)
    truth = quat_to_matrix(quaternion).T @ (CAN - position)  # the can's axis in the optical frame
    seen = np.array([found["x"], found["y"], found["z"]])
    assert abs(truth[0]) < 0.1  # the robot stopped with the can near the middle columns (3 px: 3 cm at 2.8 m, and
    # the visible blob's centre may sit a few pixels off the can's axis)
    error = seen - (truth - [0.0, 0.0, CAN_RADIUS])
    assert abs(error[0]) < LATERAL, (seen, truth)
    assert np.linalg.norm(error[1:]) < TOLERANCE, (seen, truth)
