"""One colour per entity from the scene description everywhere (issue 28: the trash boxes were grey in the camera
and green in the viewer): the cameras of both backends paint a URDF object's links with the colours of
``sim.scene`` (which the viewer and ``/sigcore/scene`` draw), the URDF's own or the world file's ``color``.
Rendered for real (MuJoCo through EGL/OSMesa as ``MUJOCO_GL`` says, PyBullet's TinyRenderer)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sigcore.sim import Simulation
from sigcore.world import parse_world
from sigcore.world.appearance import link_colors

ROOT = Path(__file__).parent.parent
TRASHBOX = ROOT / "worlds" / "models" / "trashbox" / "trashbox.urdf"
WORLD = f"""<world name="colours" timestep="0.002">
  <robot name="bot" urdf="{ROOT / 'tests' / 'data' / 'sim' / 'minibot.urdf'}" pose="0 0 0 0 0 0">
    <drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.36"/>
    <camera name="head" link="base_link" pose="0.1 0 0.2" width="160" height="120" rate="10" type="rgb"/>
  </robot>
  <object name="trashbox" urdf="{TRASHBOX}" static="true" pose="0.8 0 0 0 0 0"{{color}}/>
</world>
"""
"""The head camera, 0.2 m up, looks straight at the near wall of a trash box 0.49 m ahead: the centre of the image
is that wall."""


def chromaticity(rgb: np.ndarray) -> np.ndarray:
    """(r, g, b) / (r + g + b): the colour without its brightness (the lights scale all three channels alike)."""
    rgb = np.asarray(rgb, dtype=float)[:3]
    return rgb / rgb.sum()


@pytest.fixture(params=["mujoco", "bullet"])
def backend(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.mark.parametrize("color", ["", ' color="0.9 0.1 0.6 1"'], ids=["urdf-colour", "world-colour"])
def test_the_camera_shows_a_trash_box_in_its_scene_colour(tmp_path: Path, backend: str, color: str) -> None:
    """The camera's pixels of the trash box have the chromaticity of its colour in sim.scene (what the viewer
    draws) within 0.02: the URDF's green material, or the world file's colour that replaces it."""
    path = tmp_path / "colours.xml"
    path.write_text(WORLD.format(color=color))
    sim = Simulation(parse_world(path), backend)
    try:
        scene = {v.color for v in sim.scene.entities["trashbox"].visuals}
        assert len(scene) == 1
        expected = scene.pop()
        assert expected == ((0.9, 0.1, 0.6, 1.0) if color else (0.2, 0.55, 0.3, 1.0))
        sim.step(1)
        frame = sim.cameras.grab(sim.cameras.find("bot", "head"))
        assert frame.rgb is not None
        patch = frame.rgb[50:70, 70:90].reshape(-1, 3).astype(float)
        assert patch.std(axis=0).max() < 5.0  # one flat wall fills the patch
        seen = chromaticity(patch.mean(axis=0))
        assert np.abs(seen - chromaticity(np.array(expected))).max() < 0.02, (seen, expected)
    finally:
        sim.cameras.close()


def test_mujoco_geoms_carry_the_scene_colour_of_their_link(tmp_path: Path) -> None:
    """Every collision geom of the trash box and of the robot in the MuJoCo model has the scene colour of its link
    (link_colors), exactly."""
    path = tmp_path / "colours.xml"
    path.write_text(WORLD.format(color=""))
    world = parse_world(path)
    sim = Simulation(world, "mujoco")
    model = sim.backend.model  # type: ignore[attr-defined]
    checked = 0
    for entity in world.entities:
        colors = link_colors(world, entity)
        assert colors, entity.name
        for g in range(model.ngeom):
            body = model.body(model.geom_bodyid[g]).name
            if body.startswith(f"{entity.name}/") and model.geom_contype[g]:
                link = body.split("/", 1)[1]
                if link in colors:
                    assert tuple(model.geom_rgba[g]) == pytest.approx(colors[link]), (body, link)
                    checked += 1
    assert checked >= 6  # the trash box's five walls and floor, and the robot's links
    sim.cameras.close()
