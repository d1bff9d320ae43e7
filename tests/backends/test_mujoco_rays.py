"""MuJoCo only: ray distances exact to 1e-9 m (the conformance suite's rays: test_conformance_sensing.py)."""

from __future__ import annotations

import numpy as np


def test_transparent_object_is_hit(make_world, build_mujoco) -> None:
    """A fully transparent object (alpha 0) is still seen by rays: lidars see collision geometry."""
    b = build_mujoco(make_world('<object name="glass" shape="box" size="0.2 0.2 0.2" static="true" '
                                'color="1 1 1 0" pose="1 0 0.1"/>'))
    assert abs(b.ray_cast(np.array([0.0, 0.0, 0.1]), np.array([[1.0, 0.0, 0.0]]), 10.0)[0] - 0.9) < 1e-9
