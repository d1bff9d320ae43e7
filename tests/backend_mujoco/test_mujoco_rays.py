"""Ray casting in a closed box room, against analytic distances."""

from __future__ import annotations

import math

import numpy as np
from mujoco_worlds import robot

# Inner faces of the walls: x = -2 .. 2.5, y = -1.5 .. 1.5; walls 1 m high.
ROOM = (
    '<object name="wall_e" shape="box" size="0.2 3.4 1" static="true" pose="2.6 0 0.5"/>'
    '<object name="wall_w" shape="box" size="0.2 3.4 1" static="true" pose="-2.1 0 0.5"/>'
    '<object name="wall_n" shape="box" size="4.9 0.2 1" static="true" pose="0.25 1.6 0.5"/>'
    '<object name="wall_s" shape="box" size="4.9 0.2 1" static="true" pose="0.25 -1.6 0.5"/>'
)
X_MIN, X_MAX, Y_MIN, Y_MAX = -2.0, 2.5, -1.5, 1.5


def _fan(n: int) -> tuple[np.ndarray, np.ndarray]:
    angles = np.linspace(-math.pi, math.pi, n, endpoint=False) + 0.0123
    return angles, np.stack([np.cos(angles), np.sin(angles), np.zeros(n)], axis=1)


def _room_distance(origin: np.ndarray, d: np.ndarray) -> float:
    ts = []
    for lo, hi, o, v in ((X_MIN, X_MAX, origin[0], d[0]), (Y_MIN, Y_MAX, origin[1], d[1])):
        if v > 1e-12:
            ts.append((hi - o) / v)
        elif v < -1e-12:
            ts.append((lo - o) / v)
    return min(ts)


def test_room_distances_exclude_own_robot(make_world, build) -> None:
    """From the lidar link, every ray hits a wall at the analytic distance (within 1 cm) through the own
    arm."""
    b = build(make_world(ROOM + robot(pose=f"0.3 -0.2 0 0 0 {math.radians(30)}")))
    origin = b.get_pose("bot", "lidar_link")[0]
    _, dirs = _fan(360)
    dist = b.ray_cast(origin, dirs, 10.0, exclude="bot")
    expected = np.array([_room_distance(origin, d) for d in dirs])
    np.testing.assert_allclose(dist, expected, atol=0.01)


def test_own_robot_hit_without_exclude(make_world, build) -> None:
    """Without exclude, the ray backwards from the lidar hits the robot's own arm 0.17 m away (0.2 -
    radius)."""
    b = build(make_world(ROOM + robot()))
    origin = b.get_pose("bot", "lidar_link")[0]
    back = np.array([[-1.0, 0.0, 0.0]])
    assert abs(b.ray_cast(origin, back, 10.0)[0] - (0.2 - 0.03)) < 1e-9
    assert abs(b.ray_cast(origin, back, 10.0, exclude="bot")[0] - (0.1 - X_MIN)) < 1e-9


def test_max_range_gives_inf(make_world, build) -> None:
    """Rays with nothing within max_range return inf; the others their distance."""
    b = build(make_world(ROOM + robot()))
    origin = b.get_pose("bot", "lidar_link")[0]
    dirs = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    dist = b.ray_cast(origin, dirs, 2.0, exclude="bot")
    assert dist[0] == np.inf  # east wall 2.4 m away
    assert abs(dist[1] - 1.5) < 1e-9
    assert dist[2] == np.inf  # up: open sky


def test_other_entities_are_hit(make_world, build) -> None:
    """Objects, humans and other robots are hit; the exclusion is restored after the cast."""
    b = build(make_world(ROOM + robot() + '<human name="h" pose="1.5 0 0"/>'
                         '<object name="o" shape="box" size="0.2 0.2 0.2" pose="0 1 0.25"/>'))
    origin = b.get_pose("bot", "lidar_link")[0]
    slanted = np.array([-0.1, 1.0, 0.0])
    dirs = np.array([[1.0, 0.0, 0.0], slanted / np.linalg.norm(slanted)])
    dist = b.ray_cast(origin, dirs, 10.0, exclude="bot")
    r_body = 0.09 * 1.7
    assert abs(dist[0] - (1.5 - r_body - 0.1)) < 1e-6
    assert 0.85 < dist[1] < 0.95
    groups = b.model.geom_group.copy()
    b.ray_cast(origin, dirs, 10.0, exclude="h")
    np.testing.assert_array_equal(b.model.geom_group, groups)


def test_transparent_object_is_hit(make_world, build) -> None:
    """A fully transparent object (alpha 0) is still seen by rays: lidars see collision geometry."""
    b = build(make_world('<object name="glass" shape="box" size="0.2 0.2 0.2" static="true" color="1 1 1 0" '
                         'pose="1 0 0.1"/>'))
    assert abs(b.ray_cast(np.array([0.0, 0.0, 0.1]), np.array([[1.0, 0.0, 0.0]]), 10.0)[0] - 0.9) < 1e-9


def test_rays_see_moved_state(make_world, build) -> None:
    """A ray cast right after set_pose sees the object where it was put."""
    b = build(make_world(ROOM + '<object name="o" shape="box" size="0.2 0.2 0.2" pose="0 1 0.25"/>'))
    b.set_pose("o", np.array([1.0, 0.0, 0.25]))
    dist = b.ray_cast(np.array([0.0, 0.0, 0.25]), np.array([[1.0, 0.0, 0.0]]), 10.0)
    assert abs(dist[0] - 0.9) < 1e-9
