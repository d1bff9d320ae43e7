"""MuJoCo only: the plugin's registration, and URDF link friction in the model arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conformance_worlds import robot
from sigcore_backend_mujoco import MujocoBackend

from sigcore import plugins


def test_registered_as_mujoco() -> None:
    """The plugin registers MujocoBackend under the name 'mujoco'."""
    assert plugins.get_backend("mujoco") is MujocoBackend
    assert MujocoBackend.name == "mujoco"


def test_urdf_link_friction(make_world, build_mujoco, tmp_path: Path) -> None:
    """Link friction comes from <gazebo><mu1> or PyBullet's <contact><lateral_friction>; 0 is frictionless."""
    urdf = (tmp_path / "bot.urdf").read_text()
    contact = '<contact><lateral_friction value="0.3"/></contact>'
    urdf = urdf.replace('<link name="hand">', '<link name="hand">' + contact)
    (tmp_path / "bot.urdf").write_text(urdf)
    b = build_mujoco(make_world(robot()))  # the world reads its URDFs once, when parsed
    geom = {link: int(np.flatnonzero(b.model.geom_bodyid == b.model.body(f"bot/{link}").id)[0])
            for link in ("caster_f", "hand", "arm_1")}
    assert b.model.geom_friction[geom["caster_f"], 0] == 0.0
    assert b.model.geom_condim[geom["caster_f"]] == 1
    assert b.model.geom_friction[geom["hand"], 0] == pytest.approx(0.3)
    assert b.model.geom_friction[geom["arm_1"], 0] == pytest.approx(1.0)
