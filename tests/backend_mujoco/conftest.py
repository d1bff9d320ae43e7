"""Fixtures for the MuJoCo backend tests: tiny worlds written from inline XML to ``tmp_path``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from mujoco_worlds import BOT_URDF
from sigcore_backend_mujoco import MujocoBackend

from sigcore.world import World, parse_world

WorldFactory = Callable[..., World]


@pytest.fixture
def make_world(tmp_path: Path) -> WorldFactory:
    """``make_world(body_xml, timestep=0.002)``: a world file with the bot URDF next to it, parsed."""
    (tmp_path / "bot.urdf").write_text(BOT_URDF)

    def make(body: str, timestep: float = 0.002, name: str = "w") -> World:
        path = tmp_path / f"{name}.xml"
        path.write_text(f'<world name="{name}" timestep="{timestep}">\n{body}\n</world>\n')
        return parse_world(path)

    return make


@pytest.fixture
def build() -> Callable[[World], MujocoBackend]:
    """``build(world)``: a MuJoCo backend holding ``world``."""

    def make(world: World) -> MujocoBackend:
        backend = MujocoBackend()
        backend.build(world)
        return backend

    return make
