"""Shared fixtures (the core test world on the MuJoCo backend) and the suite's tiers, workers and order
(``tests/tiers.py``)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import tiers

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


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--store-durations", action="store_true",
                     help="write the seconds of the tests that take 1 s or more to tests/durations.json (the order "
                          "parallel work is handed out in; tests/tiers.py)")


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("--store-durations"):
        config.pluginmanager.register(tiers.DurationStore(), "sigcore-durations")


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    return tiers.auto_workers()


@pytest.hookimpl(tryfirst=True)  # before xdist reads the xdist_group markers
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    tiers.arrange(config, items)


@pytest.fixture(autouse=True)
def no_log_filter_left() -> Iterator[None]:
    """A test leaves no log filter on the ``sigcore`` loggers (a ROS 2 transport that was started and never stopped
    leaves its once-per-kind filter, which would hide later tests' warnings)."""
    import logging

    names = ("sigcore", "sigcore.api", "sigcore.ros2")
    yield
    left = {n: logging.getLogger(n).filters for n in names if logging.getLogger(n).filters}
    for n in left:
        logging.getLogger(n).filters.clear()
    assert not left, f"log filters left on {left}: a transport started by this test was not stopped"
