"""The inner volume of a trash box, read from its URDF, and the point-in-box test."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from referee_worlds import TRASHBOX
from sigcore_referee.boxes import TrashBox, inner_volume
from sigcore_referee.exceptions import BoxGeometryError

from sigcore.geometry import quat_from_rpy


def _urdf(tmp_path: Path, collisions: str, links: int = 1) -> Path:
    extra = "".join(f'<link name="l{i}"/>' for i in range(1, links))
    path = tmp_path / "box.urdf"
    path.write_text(f'<robot name="b"><link name="l0">{collisions}</link>{extra}</robot>')
    return path


def test_trashbox_model_inner_volume() -> None:
    """worlds/models/trashbox: 0.40 x 0.40 opening between the walls, from the floor top (0.02) to the rim (0.40)."""
    assert inner_volume("tb", TRASHBOX) == pytest.approx((-0.2, -0.2, 0.02, 0.2, 0.2, 0.4))


def test_scale_scales_the_volume() -> None:
    """A URDF object's scale scales the inner volume."""
    assert inner_volume("tb", TRASHBOX, 2.0) == pytest.approx((-0.4, -0.4, 0.04, 0.4, 0.4, 0.8))


def test_off_centre_model(tmp_path: Path) -> None:
    """A box whose frame is at a corner: the volume is found around the footprint's centre."""
    walls = "".join(f'<collision><origin xyz="{x} {y} {z}"/><geometry><box size="{s}"/></geometry></collision>'
                    for x, y, z, s in [(0.5, 0.3, 0.05, "1 0.6 0.1"), (0.05, 0.3, 0.5, "0.1 0.6 1"),
                                       (0.95, 0.3, 0.5, "0.1 0.6 1"), (0.5, 0.05, 0.5, "0.8 0.1 1"),
                                       (0.5, 0.55, 0.5, "0.8 0.1 1")])
    assert inner_volume("b", _urdf(tmp_path, walls)) == pytest.approx((0.1, 0.1, 0.1, 0.9, 0.5, 1.0))


@pytest.mark.parametrize(("collisions", "links", "reason"), [
    ('<collision><geometry><cylinder radius="0.2" length="0.4"/></geometry></collision>', 1, "only <box>"),
    ('<collision><geometry><box size="0.4 0.4 0.4"/></geometry></collision>', 1, "floor with four walls"),
    ('<collision><origin rpy="0 0 0.3"/><geometry><box size="1 1 1"/></geometry></collision>', 1, "rotated"),
    ('<collision><geometry><box size="1 1 1"/></geometry></collision>', 2, "only one-link boxes"),
    ("", 1, "no collision geometry"),
])
def test_unreadable_models_ask_for_box_inner(tmp_path: Path, collisions: str, links: int, reason: str) -> None:
    """Models the reader does not understand raise BoxGeometryError naming the box and asking for box_inner."""
    with pytest.raises(BoxGeometryError, match="box_inner") as info:
        inner_volume("bin_7", _urdf(tmp_path, collisions, links))
    assert reason in str(info.value) and "'bin_7'" in str(info.value)


def test_contains_follows_the_box_pose() -> None:
    """The test is done in the box's frame: a turned, moved box moves its volume."""
    box = TrashBox("b", frozenset({"can"}), (-0.1, -0.3, 0.0, 0.1, 0.3, 0.4))
    q = quat_from_rpy(0, 0, math.pi / 2)
    at = np.array([5.0, 1.0, 0.0])
    assert box.contains(np.array([5.25, 1.0, 0.2]), at, q)  # world +x is the turned box's -y axis
    assert not box.contains(np.array([5.0, 1.25, 0.2]), at, q)
    assert not box.contains(np.array([5.0, 1.0, 0.45]), at, q)  # above the rim
    assert box.contains(np.array([5.0, 1.0, 0.0]), at, q)
