"""The agents' camera services, SIGVerse's ``captureView`` and ``distanceSensor``, called through the API table on
both backends (tests/data/sim/camera.xml: the robot's head camera looks at a wall 2.85 m ahead, a red can on the
left); refusals name what would be valid; spawned and deleted robots bring and take their cameras."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sigcore.api.call import call
from sigcore.api.table import api_table
from sigcore.sim import Simulation
from sigcore.world import parse_world

DATA = Path(__file__).parent / "data" / "sim"
ENTRIES = {e.suffix: e for e in api_table()}


@pytest.fixture(params=["mujoco", "bullet"])
def sim(request: pytest.FixtureRequest):
    s = Simulation(parse_world(DATA / "camera.xml"), request.param)
    s.step(100)
    yield s
    s.cameras.close()


def _image(fields: dict, channels: int, dtype: type) -> np.ndarray:
    data = np.asarray(fields["data"], dtype=np.uint8)
    return data.view(dtype).reshape(fields["height"], fields["width"], *([channels] if channels > 1 else []))


def test_capture_view_gives_the_current_step_in_colour_depth_and_intrinsics(sim: Simulation) -> None:
    """One image now, stamped with the current step, in the camera's optical frame: rgb8 160x120 with the red can in
    the left half, 32FC1 depth with the wall at the centre, and the CameraInfo of the camera."""
    out = call(sim, ENTRIES["_captureView"], "bot", {"camera": ""})
    assert out["success"], out["message"]
    image, depth, info = out["image"], out["depth"], out["camera_info"]
    assert image["header"] == depth["header"] == info["header"] == {"stamp": 100 * 2_000_000,
                                                                     "frame_id": "head_optical_frame"}
    assert (image["encoding"], image["width"], image["height"], image["step"]) == ("rgb8", 160, 120, 480)
    assert (depth["encoding"], depth["step"]) == ("32FC1", 640)
    rgb = _image(image, 3, np.uint8)
    red = (rgb[..., 0] > 90) & (rgb[..., 1] < 60) & (rgb[..., 2] < 60)
    assert red.sum() > 20 and not red[:, 80:].any()
    d = _image(depth, 1, np.float32)
    assert abs(float(d[60, 80]) - 2.85) < 0.05
    assert info["k"] == sim.cameras.find("bot").info["k"]


def test_distance_sensor_equals_the_depth_along_the_axis(sim: Simulation) -> None:
    """distanceSensor casts one ray along the optical axis: it equals the depth image's centre within 1 mm (the
    image's centre lies between pixels: the four around it are averaged)."""
    out = call(sim, ENTRIES["_distanceSensor"], "bot", {"camera": "head"})
    assert out["success"], out["message"]
    frame = sim.cameras.grab(sim.cameras.find("bot", "head"))
    assert frame.depth is not None
    centre = float(frame.depth[59:61, 79:81].mean())
    assert abs(out["distance"] - centre) < 1e-3, (out["distance"], centre)


def test_camera_services_refuse_what_does_not_exist(sim: Simulation) -> None:
    """An unknown camera is refused with the robot's cameras; the simulation steps on."""
    for suffix in ("_captureView", "_distanceSensor"):
        out = call(sim, ENTRIES[suffix], "bot", {"camera": "eyes"})
        assert not out["success"]
        assert "robot 'bot' has no camera 'eyes'; its cameras: head" in out["message"]
    sim.step(10)
    assert sim.step_count == 110


def test_a_robot_without_a_camera_is_told_how_to_add_one() -> None:
    """A robot with no <camera>: both services answer that it has none and how to add one."""
    s = Simulation(parse_world(DATA / "world.xml"), "mujoco")
    for suffix in ("_captureView", "_distanceSensor"):
        out = call(s, ENTRIES[suffix], "bot", {"camera": ""})
        assert not out["success"] and "robot 'bot' has no <camera>; add one in the world file" in out["message"]


def test_a_spawned_robot_brings_its_camera_and_a_deleted_one_takes_it(sim: Simulation) -> None:
    """A second robot spawned with a camera is captured under its own prefixed optical frame and its topics are
    declared; deleting it withdraws them and its camera is gone."""
    robot = sim.world.agent("bot").model_copy(update={"name": "bot2"})
    sim.entities.add([robot])
    topics = {p.topic for p in sim.publications.declared}
    assert {"/bot2/head/image_raw", "/bot2/head/depth/image_raw", "/bot2/head/camera_info"} <= topics
    out = call(sim, ENTRIES["_captureView"], "bot2", {"camera": "head"})
    assert out["success"], out["message"]
    assert out["image"]["header"]["frame_id"] == "bot2/head_optical_frame"
    assert "bot2/head_optical_frame" in sim.frames.static()
    sim.entities.delete(["bot2"])
    assert not any(p.topic.startswith("/bot2/") for p in sim.publications.declared)
    assert "bot2/head_optical_frame" not in sim.frames.static()
    assert not call(sim, ENTRIES["_captureView"], "bot2", {"camera": "head"})["success"]
