"""Take docs/people.md's picture of people walking: docs/images/people_walking.png.

Three people of 1.7, 1.6 and 1.85 m walk at 1.2, 0.8 and 0.5 m/s (the last one turning) for 0.8 s of simulated
time on MuJoCo, rendered headless (``MUJOCO_GL=egl`` unless set) by the backend's camera renderer, seen from the
side.
Usage: .venv/bin/python scripts/people_picture.py
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from sigcore.backend import CameraView
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "images" / "people_walking.png"
WORLD = """<world name="people" timestep="0.002">
  <human name="a" pose="-2.6 0 0"/>
  <human name="b" pose="-0.9 1.2 0" height="1.6"/>
  <human name="c" pose="0.9 2.4 0 0 0 0.3" height="1.85"/>
</world>
"""


def main() -> None:
    os.environ.setdefault("MUJOCO_GL", "egl")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "people.xml"
        path.write_text(WORLD)
        sim = Simulation(parse_world(path), "mujoco")
    for person, linear, angular in (("a", 1.2, 0.0), ("b", 0.8, 0.0), ("c", 0.5, -0.2)):
        sim.inputs.person_velocity(person, linear, angular)
    sim.step(400)
    forward = np.array([0.0, 1.0, -0.12]) / np.linalg.norm([0.0, 1.0, -0.12])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    axes = np.stack([right, np.cross(forward, right), forward], axis=1)  # optical: x right, y down, z forward
    width, height = 800, 500
    view = CameraView(np.array([-0.6, -4.0, 1.4]), axes, width, height, 520.0, (width - 1) / 2, (height - 1) / 2,
                      0.05, 30.0, True, False)
    renderer = sim.backend.renderer()
    try:
        ((rgb, _),) = renderer.render(renderer.snapshot(), [view])
    finally:
        renderer.close()
    Image.fromarray(np.asarray(rgb)).save(OUT)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
