"""The drive state: ``_setWheel`` sets the geometry that cmd_vel and the wheel odometry use; a reset restores it."""

from __future__ import annotations

import math

import pytest

from sigcore.agent.exceptions import ApiError
from sigcore.api import api_table, call
from sigcore.sim import Simulation
from sigcore.sim.drive import DriveState
from sigcore.world.models import Drive

SET_WHEEL = next(e for e in api_table() if e.suffix == "_setWheel")


def test_set_wheel_replaces_the_geometry_until_reset(sim: Simulation) -> None:
    """_setWheel changes the geometry the simulation reports; Simulation.reset() restores the world file's."""
    assert sim.entities.drive("bot").geometry() == (0.1, 0.36)
    r = call(sim, SET_WHEEL, "bot", {"wheel_radius": 0.2, "wheel_distance": 0.5})
    assert r["success"], r["message"]
    assert sim.entities.drive("bot").geometry() == (0.2, 0.5) == sim.robot("bot").wheel_geometry()
    assert sim.entities.drive("bot").model.radius == 0.1  # the world file's <drive> is unchanged
    sim.reset()
    assert sim.entities.drive("bot").geometry() == (0.1, 0.36)


@pytest.mark.parametrize(("radius", "distance", "says"), [
    (float("nan"), 0.36, "wheel radius [m] must be a finite number with 0 < wheel radius <= 5, got nan"),
    (float("inf"), 0.36, "wheel radius [m] must be a finite number"),
    (0.0, 0.36, "0 < wheel radius <= 5, got 0.0"),
    (-0.1, 0.36, "0 < wheel radius <= 5, got -0.1"),
    (0.1, -1.0, "wheel separation [m] must be a finite number with 0 < wheel separation <= 20, got -1.0"),
    (0.1, float("-inf"), "wheel separation [m] must be a finite number"),
    (0.1, 25.0, "0 < wheel separation <= 20, got 25.0"),
])
def test_set_wheel_refuses_bad_values(sim: Simulation, radius: float, distance: float, says: str) -> None:
    """A non-finite, non-positive or too large value is refused with what is valid, and nothing changes."""
    r = call(sim, SET_WHEEL, "bot", {"wheel_radius": radius, "wheel_distance": distance})
    assert not r["success"] and says in r["message"]
    assert sim.entities.drive("bot").geometry() == (0.1, 0.36)


def test_set_wheel_on_an_object_is_refused(sim: Simulation) -> None:
    """Only robots with a <drive> have a geometry: an object is refused naming the robots."""
    with pytest.raises(ApiError, match="not a robot; robots: bot"):
        sim.robot("cube").set_wheel(0.1, 0.3)


def test_base_velocity_uses_the_geometry_set(sim: Simulation) -> None:
    """set_base_velocity (cmd_vel) turns (v, w) into wheel speeds with the geometry now in use."""
    bot = sim.robot("bot")
    bot.set_wheel(0.2, 0.5)
    bot.set_base_velocity(0.3, 0.4)
    sim.step(250)
    left = sim.backend.get_joint_velocity("bot", "wheel_l_joint")
    right = sim.backend.get_joint_velocity("bot", "wheel_r_joint")
    assert left == pytest.approx((0.3 - 0.4 * 0.25) / 0.2, abs=0.02)
    assert right == pytest.approx((0.3 + 0.4 * 0.25) / 0.2, abs=0.02)


def test_odometry_uses_the_geometry_set(sim: Simulation) -> None:
    """With the radius declared twice the URDF's, the odometry counts twice the distance the body drives; after a
    reset it matches the body again (within 5 %: spin-up and slip)."""
    bot = sim.robot("bot")
    odo = sim.entities.enable_odometry("bot")
    bot.set_wheel(0.2, 0.36)
    x0 = bot.position()[0]
    bot.set_wheel_velocity(3.0, 3.0)
    sim.step(500)
    driven = bot.position()[0] - x0
    assert driven == pytest.approx(3.0 * 0.1 * 1.0, rel=0.05)
    assert odo.state.x == pytest.approx(2 * driven, rel=0.05)
    sim.reset()
    x0 = bot.position()[0]
    bot.set_wheel_velocity(3.0, 3.0)
    sim.step(500)
    assert odo.state.x == pytest.approx(bot.position()[0] - x0, rel=0.05)


def test_drive_state_conversions_are_inverse() -> None:
    """wheel_speeds and body_velocity invert each other for the geometry in use."""
    state = DriveState("r", Drive(left="l", right="r", radius=0.1, separation=0.4))
    state.set_geometry(0.05, 0.3)
    left, right = state.wheel_speeds(0.5, -1.2)
    v, w = state.body_velocity(left, right)
    assert (v, w) == (pytest.approx(0.5), pytest.approx(-1.2))
    assert math.isclose(right - left, -1.2 * 0.3 / 0.05)
    state.reset()
    assert state.geometry() == (0.1, 0.4) and state.cmd_vel_timeout == 0.5
