"""Fixtures of the ROS 2 transport tests (the process helpers are in rosproc.py)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from rosproc import ALL_AGENTS, WORLD, SimProcess, start_sim


@pytest.fixture(scope="module")
def sim_proc(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SimProcess]:
    """One real-time simulation of tests/data/sim/world.xml with the ROS 2 transport for the whole module, every
    agent with its sig_ros endpoints (``sigros_agents=all``: the default leaves out the plain objects')."""
    sim = start_sim(tmp_path_factory.mktemp("ros2"), WORLD, "--realtime", *ALL_AGENTS)
    try:
        yield sim
    finally:
        sim.stop()

