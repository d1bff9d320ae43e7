"""Fixtures of the IK tests: the clean-up world (robot_000, two arms) and the arm6 world (one 6-DoF arm)."""

from __future__ import annotations

from pathlib import Path

import pytest

from sigcore.sim import Simulation
from sigcore.world import World, parse_world

WORLDS = Path(__file__).parent.parent.parent / "worlds"


@pytest.fixture(scope="session")
def cleanup_world() -> World:
    """worlds/cleanup.xml (robot_000 with left_arm and right_arm)."""
    return parse_world(WORLDS / "cleanup.xml")


@pytest.fixture(scope="session")
def arm6_world() -> World:
    """worlds/arm6.xml (arm_0 with the chain 'arm')."""
    return parse_world(WORLDS / "arm6.xml")


@pytest.fixture
def arm6_sim(arm6_world: World) -> Simulation:
    """A fresh MuJoCo simulation of the arm6 world."""
    return Simulation(arm6_world, "mujoco")


@pytest.fixture(scope="module")
def cleanup_sim(cleanup_world: World) -> Simulation:
    """A MuJoCo simulation of the clean-up world, shared by a module's tests."""
    return Simulation(cleanup_world, "mujoco")
