"""Poses, velocities, free fall, wrenches, masses and centres of mass."""

from __future__ import annotations

import numpy as np
import pytest

STICK_URDF = """<robot name="stick">
  <link name="stick_link">
    <inertial><origin xyz="0.3 0 0"/><mass value="2"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial>
    <collision><origin xyz="0.3 0 0"/><geometry><box size="0.6 0.05 0.05"/></geometry></collision>
  </link>
</robot>"""


def test_pose_after_step_matches_qpos(make_world, build) -> None:
    """After a step, get_pose describes the integrated state (not the state before the step)."""
    b = build(make_world('<object name="o" shape="sphere" size="0.1" pose="0 0 5"/>'))
    b.set_velocity("o", linear=np.array([3.0, 0.0, 0.0]))
    b.step()
    np.testing.assert_allclose(b.get_pose("o")[0], b.data.qpos[0:3], atol=1e-15)
    assert b.get_pose("o")[0][0] == pytest.approx(3.0 * 0.002)
