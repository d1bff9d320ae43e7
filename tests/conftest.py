"""Shared fixtures: the core test world on the MuJoCo backend."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from sigcore import plugins
from sigcore.sim import Simulation
from sigcore.world import World, parse_world

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).parent.parent


@pytest.fixture(scope="session")
def core_world() -> World:
    """The core tests' world (a small robot, objects, a human, a bare agent)."""
    return parse_world(DATA / "sim" / "world.xml")


@pytest.fixture
def sim(core_world: World) -> Simulation:
    """A fresh simulation of the core world on MuJoCo."""
    return Simulation(core_world, "mujoco")


@pytest.fixture
def fresh_plugins(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """The plugin registry starts empty (the next lookup rediscovers the installed plugins) and forgets the
    in-process plugins the test registered."""
    monkeypatch.delenv(plugins.DISABLE_ENV, raising=False)
    plugins.reset_for_tests()
    yield
    plugins.reset_for_tests()
