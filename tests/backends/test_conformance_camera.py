"""Conformance: camera images on every backend — depth, where things appear, the intrinsics CameraInfo states, the
step an image shows — and the two backends agreeing on what a camera sees.

The camera sits 0.5 m above the origin on a fixed robot and looks along +x: in its optical frame a world point
(x, y, z) is at X = -y (right), Y = 0.5 - z (down), Z = x (forward). That is computed here, independently of the
code under test.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sigcore.sim import Simulation
from sigcore.sim.camera import CameraFrame
from sigcore.world import World

EYE_URDF = """<?xml version="1.0"?>
<robot name="eye"><link name="base_link">
  <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  <visual><geometry><box size="0.05 0.05 0.05"/></geometry></visual>
  <collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision>
</link></robot>
"""
CAMERA_Z = 0.5
W, H = 320, 240
DEPTH_TOLERANCE = 1e-3
"""Depth at a pixel against the true distance [m] (the issue's 1 mm)."""
AGREE_SHARE = 0.99
"""Share of pixels on which both backends' depths agree within 1 mm; the others lie on silhouette edges, where
the two rasterisers may give a boundary pixel to different surfaces."""


def _world(tmp_path: Path, make_world, objects: str, camera: str = "") -> World:
    (tmp_path / "eye.urdf").write_text(EYE_URDF)
    return make_world(f'<robot name="eye" urdf="eye.urdf" fixed="true">'
                      f'<camera name="cam" link="base_link" pose="0 0 {CAMERA_Z}" width="{W}" height="{H}" '
                      f'rate="50" {camera}/></robot>{objects}')


def _frames(sim: Simulation, steps: int, before_step=None) -> list[CameraFrame]:
    frames: list[CameraFrame] = []
    sim.events.subscribe("camera", frames.append)
    for _ in range(steps):
        if before_step is not None:
            before_step(sim.step_count + 1)
        sim.step()
    sim.cameras.settle()
    sim.cameras.close()
    assert sim.cameras.failure is None, sim.cameras.failure
    return frames


def _red(rgb: np.ndarray) -> np.ndarray:
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    return (r > 90) & (g < 60) & (b < 60)


WALL = '<object name="wall" shape="box" size="0.2 3 2" pose="1.8 0 1" static="true" color="0.2 0.2 0.9 1"/>'


def test_depth_at_the_centre_is_the_distance_to_a_box(tmp_path: Path, make_world, simulate) -> None:
    """A box face 1.7 m ahead, square to the axis: the four centre pixels read 1.7 m within 1 mm; the colour there
    is the box's (blue), and an rgbd camera gives both images at the stated size."""
    frames = _frames(simulate(_world(tmp_path, make_world, WALL)), 20)
    assert [f.step for f in frames] == [10, 20]
    f = frames[-1]
    assert f.rgb is not None and f.rgb.shape == (H, W, 3) and f.rgb.dtype == np.uint8
    assert f.depth is not None and f.depth.shape == (H, W) and f.depth.dtype == np.float32
    centre = f.depth[H // 2 - 1:H // 2 + 1, W // 2 - 1:W // 2 + 1]
    assert np.all(np.abs(centre - 1.7) < DEPTH_TOLERANCE), centre
    r, g, b = (int(c) for c in f.rgb[H // 2, W // 2])
    assert b > 100 and b > 2 * r and b > 2 * g, (r, g, b)


def test_a_red_box_left_of_the_axis_is_in_the_left_half(tmp_path: Path, make_world, simulate) -> None:
    """A red box 0.4 m left of the axis (+y) appears in the left half of the image, and nowhere right of it."""
    box = '<object name="red" shape="box" size="0.2 0.2 0.2" pose="1.5 0.4 0.5" static="true" color="1 0 0 1"/>'
    f = _frames(simulate(_world(tmp_path, make_world, WALL + box)), 10)[-1]
    assert f.rgb is not None
    red = _red(f.rgb)
    assert red.sum() > 500
    assert not red[:, W // 2:].any()


def test_camera_info_projects_a_point_onto_its_pixel(tmp_path: Path, make_world, simulate) -> None:
    """With an off-centre principal point and a given focal length, CameraInfo's K projects the centre of a thin
    red plate (square to the axis, off-axis) onto the centroid of its red pixels within one pixel, and the depth
    there is the plate's distance."""
    plate = ('<object name="plate" shape="box" size="0.01 0.16 0.16" pose="2.0 -0.3 0.75" static="true" '
             'color="1 0 0 1"/>')
    frames = _frames(simulate(_world(tmp_path, make_world, plate, 'focal="250" principal="140 100"')), 10)
    f = frames[-1]
    fx, _, cx, _, fy, cy = f.info["k"][:6]
    assert (fx, fy, cx, cy) == (250.0, 250.0, 140.0, 100.0)
    assert f.info["p"] == [250.0, 0.0, 140.0, 0.0, 0.0, 250.0, 100.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    x, y, z = 2.0 - 0.005, -0.3, 0.75  # the centre of the face the camera sees
    X, Y, Z = -y, CAMERA_Z - z, x
    u, v = fx * X / Z + cx, fy * Y / Z + cy
    assert f.rgb is not None and f.depth is not None
    rows, cols = np.nonzero(_red(f.rgb))
    assert len(rows) > 50
    assert abs(cols.mean() - u) < 1.0 and abs(rows.mean() - v) < 1.0, (cols.mean(), rows.mean(), u, v)
    assert abs(f.depth[round(v), round(u)] - Z) < DEPTH_TOLERANCE
    assert f.frame == "cam_optical_frame"


def test_images_are_stamped_with_the_step_they_show(tmp_path: Path, make_world, simulate) -> None:
    """A static wall moved before every step (its face at 1.0 m + 1 cm per step): each image shows the wall where it
    was at the image's step, and is stamped with that step's time."""
    sim = simulate(_world(tmp_path, make_world, WALL))

    def move(step: int) -> None:
        sim.backend.set_pose("wall", np.array([1.1 + 0.01 * step, 0.0, 1.0]))

    frames = _frames(sim, 60, move)
    assert [f.step for f in frames] == [10, 20, 30, 40, 50, 60]
    for f in frames:
        assert f.stamp_ns == f.step * round(sim.dt * 1e9)
        assert f.depth is not None
        assert abs(float(f.depth[H // 2, W // 2]) - (1.0 + 0.01 * f.step)) < DEPTH_TOLERANCE, f.step


def test_kinds_and_depth_beyond_far(tmp_path: Path, make_world, simulate) -> None:
    """A depth-only camera gives no colour and an rgb-only one no depth; looking up into the empty sky, depth is
    +inf; a wall beyond ``far`` is +inf too."""
    depth_only = _frames(simulate(_world(tmp_path, make_world, WALL, 'type="depth" far="1.5"')), 10)[-1]
    assert depth_only.rgb is None and depth_only.depth is not None
    assert np.isinf(depth_only.depth[H // 2, W // 2])
    assert np.isinf(depth_only.depth[0, :]).all()
    rgb_only = _frames(simulate(_world(tmp_path, make_world, WALL, 'type="rgb"')), 10)[-1]
    assert rgb_only.depth is None and rgb_only.rgb is not None


def test_depth_noise_has_the_stated_spread(tmp_path: Path, make_world, simulate) -> None:
    """``noise="0.01"``: the depth on the wall scatters around 1.7 m with a standard deviation of 1 cm (within
    15 %), and the mean stays within 1 mm."""
    f = _frames(simulate(_world(tmp_path, make_world, WALL, 'noise="0.01"')), 10)[-1]
    assert f.depth is not None
    patch = f.depth[H // 2 - 20:H // 2 + 20, W // 2 - 20:W // 2 + 20].astype(float)
    assert abs(patch.std() - 0.01) < 0.0015 and abs(patch.mean() - 1.7) < 1e-3


def test_a_renderer_that_cannot_start_turns_cameras_off_not_the_run(tmp_path: Path, make_world, simulate,
                                                                     backend_name: str,
                                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """MuJoCo told to render through GLFW on a machine with no display: the renderer fails for real; the error
    names MUJOCO_GL and the packages to install, the simulation steps on, and no image is published."""
    if backend_name != "mujoco":
        pytest.skip("only MuJoCo's renderer opens an OpenGL context")
    monkeypatch.setenv("MUJOCO_GL", "glfw")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    sim = simulate(_world(tmp_path, make_world, WALL))
    frames: list[CameraFrame] = []
    sim.events.subscribe("camera", frames.append)
    sim.step(50)
    sim.cameras.settle()
    sim.cameras.close()
    assert sim.step_count == 50 and frames == []
    assert sim.cameras.failure is not None
    assert "MUJOCO_GL=glfw" in sim.cameras.failure and "libegl" in sim.cameras.failure


def _both(tmp_path: Path, make_world, objects: str) -> tuple[np.ndarray, np.ndarray]:
    world = _world(tmp_path, make_world, objects, 'far="8"')
    depth = []
    for backend in ("mujoco", "bullet"):
        f = _frames(Simulation(world, backend), 10)[-1]
        assert f.depth is not None
        depth.append(f.depth.astype(float))
    return depth[0], depth[1]


def _agreeing(a: np.ndarray, b: np.ndarray, relative: float) -> float:
    """Share of the pixels where both see something whose depths differ by at most 1 mm + ``relative`` x depth."""
    both = np.isfinite(a) & np.isfinite(b)
    return float((both & (np.abs(a - b) <= DEPTH_TOLERANCE + relative * a)).sum() / both.sum())


def _floor_depth() -> np.ndarray:
    """(H, W) the depth of the ground plane z = 0 at every pixel of the default camera (+inf above the horizon)."""
    f, cy = (W / 2) / np.tan(np.pi / 6), (H - 1) / 2
    down = (np.arange(H) - cy) / f  # Y / Z of each row
    with np.errstate(divide="ignore"):
        z = np.where(down > 0, CAMERA_Z / down, np.inf)
    return np.repeat(z[:, None], W, axis=1)


def test_both_backends_see_the_same_depth(tmp_path: Path, make_world) -> None:
    """Boxes in front of a wall: on every face square to the view, the depths of MuJoCo and PyBullet agree within
    1 mm on at least 99 % of the pixels (the rest are silhouette edges)."""
    objects = (WALL + '<object name="red" shape="box" size="0.2 0.2 0.2" pose="1.2 0.3 0.3" static="true" '
               'color="1 0 0 1"/><object name="crate" shape="box" size="0.3 0.2 0.4" pose="1.0 -0.4 0.2" '
               'static="true"/>')
    a, b = _both(tmp_path, make_world, objects)
    square = np.zeros(a.shape, dtype=bool)
    for face in (1.7, 1.1, 0.85):  # the wall's, the red box's and the crate's faces turned to the camera
        square |= np.abs(a - face) <= DEPTH_TOLERANCE
    assert square.sum() > 0.7 * a.size
    agree = np.abs(a - b) <= DEPTH_TOLERANCE
    assert (agree & square).sum() >= AGREE_SHARE * square.sum()


def test_both_backends_see_slanted_surfaces_alike(tmp_path: Path, make_world) -> None:
    """The floor up to 8 m and a box turned 0.5 rad: MuJoCo's depth is the floor plane's within 1 mm + 0.1 % of the
    distance wherever it sees the floor; PyBullet's TinyRenderer does not interpolate depth exactly across a
    surface slanted to the view and draws it nearer, within 3 % of the distance (measured: the floor 0.3 % at
    1.2 m, 2.4 % at 6.8 m), so the two agree within 3 % on at least 99 % of the pixels."""
    crate = '<object name="crate" shape="box" size="0.3 0.2 0.4" pose="1.0 -0.4 0.2 0 0 0.5" static="true"/>'
    a, b = _both(tmp_path, make_world, crate)
    floor = _floor_depth()
    seen = (floor < 7.5) & (np.abs(a - floor) < 0.01)  # the floor, not the crate
    assert seen.sum() > 0.3 * a.size
    assert np.all(np.abs(a - floor)[seen] <= DEPTH_TOLERANCE + 0.001 * floor[seen])
    assert _agreeing(a, b, 0.03) >= AGREE_SHARE
    assert np.isinf(a[~np.isfinite(floor)]).all() and np.isinf(b[~np.isfinite(floor)]).all()


def test_both_backends_see_curved_shapes_alike(tmp_path: Path, make_world) -> None:
    """A sphere and a cylinder: both renderers draw them as facets (MuJoCo's and TinyRenderer's differ), so their
    depths agree within 1 mm + 2 % of the distance on at least 97 % of the pixels."""
    objects = (WALL + '<object name="ball" shape="sphere" size="0.15" pose="1.0 -0.35 0.6" static="true" '
               'color="0 1 0 1"/><object name="can" shape="cylinder" size="0.05 0.3" pose="0.8 0.1 0.15" '
               'static="true"/>')
    a, b = _both(tmp_path, make_world, objects)
    assert _agreeing(a, b, 0.02) >= 0.97


def test_cameras_of_different_sizes_on_one_robot(tmp_path: Path, make_world, simulate) -> None:
    """A small camera and a larger one drawn in the same step: both show the wall where it is (the renderer grows
    its buffer for the larger one without garbage in either), each at its own size."""
    (tmp_path / "eye.urdf").write_text(EYE_URDF)
    world = make_world(f'<robot name="eye" urdf="eye.urdf" fixed="true">'
                       f'<camera name="small" link="base_link" pose="0 0 {CAMERA_Z}" width="160" height="120" '
                       f'rate="50"/><camera name="large" link="base_link" pose="0 0 {CAMERA_Z}" width="640" '
                       f'height="480" rate="50"/></robot>{WALL}')
    frames = _frames(simulate(world), 20)
    assert sorted((f.camera, f.step) for f in frames) == [("large", 10), ("large", 20), ("small", 10), ("small", 20)]
    for f in frames:
        assert f.depth is not None and f.rgb is not None
        h, w = f.depth.shape
        assert (w, h) == ((160, 120) if f.camera == "small" else (640, 480))
        top = slice(0, h // 2)  # the wall fills the upper half of every view (the floor shows below)
        assert np.all(np.abs(f.depth[top] - 1.7) < DEPTH_TOLERANCE)
        assert f.rgb[top, :, 2].min() > 100  # blue all over it: no garbage
