"""Ray casting in a closed box room, against analytic distances."""

from __future__ import annotations

import math

import numpy as np

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


def test_transparent_object_is_hit(make_world, build) -> None:
    """A fully transparent object (alpha 0) is still seen by rays: lidars see collision geometry."""
    b = build(make_world('<object name="glass" shape="box" size="0.2 0.2 0.2" static="true" color="1 1 1 0" '
                         'pose="1 0 0.1"/>'))
    assert abs(b.ray_cast(np.array([0.0, 0.0, 0.1]), np.array([[1.0, 0.0, 0.0]]), 10.0)[0] - 0.9) < 1e-9
