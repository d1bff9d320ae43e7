"""Cameras over ROS 2: a separate rclpy process steps a paused simulation (tests/data/sim/camera.xml, MuJoCo) by
2 s and receives the head camera's colour and depth images and CameraInfos at the configured 10 Hz, each stamped
with the step it shows, in the optical frame that /tf_static places per REP-103 (clients/camera.py)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import client_against  # noqa: E402

pytestmark = pytest.mark.ros2

WORLD = Path(__file__).resolve().parents[1] / "data" / "sim" / "camera.xml"
STEPS = 1000
"""Steps the client asks for: 2 s at 2 ms, 20 images at 10 Hz."""
EXPECTED = [round(0.1 * k, 9) for k in range(1, 21)]
MIN_SHARE = 0.9
"""Share of the 20 images a client must receive: the topics are reliable with a history of 5 at the publisher
(REP-2003's sensor default), so a client that falls more than 5 images behind may miss one."""


@pytest.fixture(scope="module")
def out(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    yield from client_against(tmp_path_factory.mktemp("camera"), WORLD, "camera.py", str(STEPS),
                              sim_args=("--paused",))


def _received(stamps: list[float]) -> list[float]:
    assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps)
    got = [round(s, 9) for s in stamps]
    assert set(got) <= set(EXPECTED), got  # every image shows a step at the camera's period
    assert len(got) >= MIN_SHARE * len(EXPECTED), got
    return got


def test_images_arrive_at_the_configured_rate_stamped_with_their_step(out: dict) -> None:
    """Colour, depth and both CameraInfos arrive at 10 Hz of simulated time: stamps are the steps 50, 100, ...,
    1000 (0.1 s apart), at least 18 of the 20 each, and every image has its CameraInfo with the same stamp."""
    assert out["stepped"]
    rgb = _received(out["rgb_stamps"])
    depth = _received(out["depth_stamps"])
    _received(out["info_stamps"])
    _received(out["depth_info_stamps"])
    assert set(rgb) <= {round(s, 9) for s in out["info_stamps"]} | set(EXPECTED)
    assert len(rgb) / (rgb[-1] - rgb[0] + 0.1) == pytest.approx(10.0, rel=0.1)
    assert len(depth) / (depth[-1] - depth[0] + 0.1) == pytest.approx(10.0, rel=0.1)


def test_images_have_the_stated_encoding_size_and_frame(out: dict) -> None:
    """rgb8 and 32FC1 images of 160x120 in head_optical_frame; the depth at the centre is the wall's distance
    (its face at x = 2.95 m, the camera 0.1 m ahead of base_link: 2.85 m, within 5 cm for where the robot settled);
    the red can left of the axis is in the image's left half."""
    assert out["rgb"] == {"encoding": "rgb8", "w": 160, "h": 120, "step": 480, "frame": "head_optical_frame"}
    depth = out["depth"]
    assert {k: depth[k] for k in ("encoding", "w", "h", "step", "frame")} == {
        "encoding": "32FC1", "w": 160, "h": 120, "step": 640, "frame": "head_optical_frame"}
    assert abs(depth["centre"] - 2.85) < 0.05
    assert len(out["red_cols"]) > 20 and max(out["red_cols"]) < 80


def test_camera_info_states_the_intrinsics(out: dict) -> None:
    """K and P: f = (width / 2) / tan(fov / 2) for the default 60° field of view, the principal point at the
    image centre ((w - 1) / 2, (h - 1) / 2); the depth image has the same K."""
    f = 80 / math.tan(math.pi / 6)
    assert out["k"] == pytest.approx([f, 0, 79.5, 0, f, 59.5, 0, 0, 1])
    assert out["p"] == pytest.approx([f, 0, 79.5, 0, 0, f, 59.5, 0, 0, 0, 1, 0])
    assert out["depth_k"] == out["k"]


def test_optical_frame_is_on_tf_static_per_rep_103(out: dict) -> None:
    """/tf_static: base_link -> head_link at the camera's pose, and head_link -> head_optical_frame rotated so that
    z looks forward and x right (w, x, y, z = 0.5, -0.5, 0.5, -0.5)."""
    frames = out["frames"]
    assert frames["head_link"]["parent"] == "base_link"
    assert frames["head_link"]["xyz"] == pytest.approx([0.1, 0.0, 0.4])
    assert frames["head_optical_frame"]["parent"] == "head_link"
    assert frames["head_optical_frame"]["wxyz"] == pytest.approx([0.5, -0.5, 0.5, -0.5])


def test_capture_view_and_distance_sensor_services(out: dict) -> None:
    """/bot_captureView answers with one image of the current step (paused at step 1000: t = 2 s) in the optical
    frame, its depth and CameraInfo; /bot_distanceSensor with the distance along the axis, which equals that depth
    image's centre within 1 cm (the centre lies between pixels); an unknown camera is refused with the robot's
    cameras."""
    s = out["services"]
    view = s["view"]
    assert view["success"], view["message"]
    assert view["stamp"] == pytest.approx(2.0) and view["frame"] == "head_optical_frame"
    assert (view["encoding"], view["w"], view["depth_encoding"], view["bytes"]) == ("rgb8", 160, "32FC1", 160 * 120 * 3)
    assert view["k"] == pytest.approx(out["k"])
    assert s["distance"]["success"] and abs(s["distance"]["distance"] - view["centre"]) < 0.01
    assert not s["wrong"]["success"] and "has no camera 'eyes'; its cameras: head" in s["wrong"]["message"]
