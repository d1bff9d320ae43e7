"""Building worlds: registration, layout, sizes, link frames, model files and errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from mujoco_worlds import robot
from sigcore_backend_mujoco import MujocoBackend

from sigcore import plugins

LINKS = ["base_link", "wheel_l", "wheel_r", "caster_f", "caster_b", "lidar_link", "arm_1", "arm_2", "hand"]

BOX_URDF = """<robot name="bin">
  <link name="bin_link">
    <inertial><origin xyz="0.05 0 0.1"/><mass value="2"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
</robot>"""

CUBE_OBJ = "\n".join(
    [f"v {x} {y} {z}" for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    + ["f 1 3 4 2", "f 5 6 8 7", "f 1 2 6 5", "f 3 7 8 4", "f 1 5 7 3", "f 2 4 8 6"]
) + "\n"


def test_registered_as_mujoco() -> None:
    """The plugin registers MujocoBackend under the name 'mujoco'."""
    assert plugins.get_backend("mujoco") is MujocoBackend
    assert MujocoBackend.name == "mujoco"


def test_urdf_link_friction(make_world, build, tmp_path: Path) -> None:
    """Link friction comes from <gazebo><mu1> or PyBullet's <contact><lateral_friction>; 0 is frictionless."""
    urdf = (tmp_path / "bot.urdf").read_text()
    contact = '<contact><lateral_friction value="0.3"/></contact>'
    urdf = urdf.replace('<link name="hand">', '<link name="hand">' + contact)
    (tmp_path / "bot.urdf").write_text(urdf)
    b = build(make_world(robot()))  # the world reads its URDFs once, when parsed
    geom = {link: int(np.flatnonzero(b.model.geom_bodyid == b.model.body(f"bot/{link}").id)[0])
            for link in ("caster_f", "hand", "arm_1")}
    assert b.model.geom_friction[geom["caster_f"], 0] == 0.0
    assert b.model.geom_condim[geom["caster_f"]] == 1
    assert b.model.geom_friction[geom["hand"], 0] == pytest.approx(0.3)
    assert b.model.geom_friction[geom["arm_1"], 0] == pytest.approx(1.0)
