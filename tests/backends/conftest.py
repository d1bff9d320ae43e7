"""Fixtures of the backend conformance suite: every test of ``test_conformance_*.py`` runs once per backend registered
through the plugin registry (``sigcore.plugins.backends()``), so a third-party backend installed next to sigcore is
tested by the same suite. The tests of ``test_mujoco_*.py`` check what only the MuJoCo backend promises (its model
and data, tighter tolerances) and run on MuJoCo alone (``build_mujoco``). Worlds are tiny inline XML written to
``tmp_path``."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from conformance_worlds import BOT_URDF

from sigcore import plugins
from sigcore.backend import Backend
from sigcore.sim import Simulation
from sigcore.world import World, parse_world

WorldFactory = Callable[..., World]

BACKENDS = sorted(plugins.backends())


@pytest.fixture(params=BACKENDS)
def backend_name(request: pytest.FixtureRequest) -> str:
    """The name of the backend under test (each registered backend in turn)."""
    return str(request.param)


@pytest.fixture
def make_world(tmp_path: Path) -> WorldFactory:
    """``make_world(body_xml, timestep=0.002)``: a world file with the bot URDF next to it, parsed."""
    (tmp_path / "bot.urdf").write_text(BOT_URDF)

    def make(body: str, timestep: float = 0.002, name: str = "w") -> World:
        path = tmp_path / f"{name}.xml"
        path.write_text(f'<world name="{name}" timestep="{timestep}">\n{body}\n</world>\n')
        return parse_world(path)

    return make


def _builder(backend_name: str) -> Callable[[World], Backend]:
    """``make(world)``: a new instance of the backend ``backend_name`` holding ``world``."""

    def make(world: World) -> Backend:
        backend = plugins.get_backend(backend_name)()
        backend.build(world)
        return backend

    return make


@pytest.fixture
def build(backend_name: str) -> Iterator[Callable[[World], Backend]]:
    """``build(world)``: a new instance of the backend under test holding ``world``."""
    yield _builder(backend_name)


@pytest.fixture
def build_mujoco() -> Callable[[World], Backend]:
    """``build_mujoco(world)``: a new MuJoCo backend holding ``world``, for the MuJoCo-only tests
    (``test_mujoco_*.py``): never parametrised over the other backends."""
    return _builder("mujoco")


@pytest.fixture
def simulate(backend_name: str) -> Callable[[World], Simulation]:
    """``simulate(world)``: a :class:`Simulation` of ``world`` on the backend under test."""

    def make(world: World) -> Simulation:
        return Simulation(world, backend_name)

    return make
