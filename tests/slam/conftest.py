"""Fixtures of the SLAM tests (helpers in slam_room.py)."""

from __future__ import annotations

import pytest
from slam_room import room_world

from sigcore.sim import Simulation


@pytest.fixture
def room_sim() -> Simulation:
    """The box room with SLAM on robot_000."""
    return Simulation(room_world(), "mujoco")
