"""The differential drive of one robot as it is now: the world's ``<drive>`` plus the geometry set by ``_setWheel``."""

from __future__ import annotations

import math

from ..agent.exceptions import ApiError
from ..world.models import Drive

MAX_RADIUS = 5.0
"""Largest wheel radius accepted [m] (the world format's bound)."""
MAX_SEPARATION = 20.0
"""Largest wheel separation accepted [m] (the world format's bound)."""


def _length(value: float, what: str, high: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ApiError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(v) or not 0.0 < v <= high:
        raise ApiError(f"{what} must be a finite number with 0 < {what.split(' [')[0]} <= {high:g}, got {v}")
    return v


class DriveState:
    """The one owner of a robot's drive geometry (wheel radius and separation [m]).

    It starts as the world file's ``<drive>``; ``set_geometry`` (sig_ros ``_setWheel``) replaces it, ``reset``
    restores the world file's. Everything that converts between body velocities and wheel speeds reads it here:
    ``set_base_velocity`` (and so ``cmd_vel``) and the wheel odometry. The physical wheels stay the URDF's, so a
    geometry that differs from them makes the robot drive and its odometry count like a mis-calibrated real robot.

    Args:
        robot: The robot's name.
        model: The world file's ``<drive>``.
    """

    def __init__(self, robot: str, model: Drive) -> None:
        self.robot = robot
        self.model = model
        self._radius = model.radius
        self._separation = model.separation

    @property
    def radius(self) -> float:
        """Wheel radius [m] now in use."""
        return self._radius

    @property
    def separation(self) -> float:
        """Distance between the wheels [m] now in use."""
        return self._separation

    @property
    def left(self) -> str:
        """Left wheel joint."""
        return self.model.left

    @property
    def right(self) -> str:
        """Right wheel joint."""
        return self.model.right

    @property
    def max_wheel_velocity(self) -> float:
        """Wheel speed limit [rad/s]."""
        return self.model.max_wheel_velocity

    @property
    def max_torque(self) -> float:
        """Wheel motor torque limit [N m]."""
        return self.model.max_torque

    @property
    def cmd_vel_timeout(self) -> float:
        """The wheels stop when no ``cmd_vel`` came for this long [s] of simulated time; 0: never."""
        return self.model.cmd_vel_timeout

    def geometry(self) -> tuple[float, float]:
        """``(radius, separation)`` [m] now in use."""
        return self._radius, self._separation

    def set_geometry(self, radius: float, separation: float) -> None:
        """Use a new wheel radius and separation [m] from now on (until :meth:`reset`).

        Raises:
            ApiError: a value that is not a finite number in ``(0, 5]`` (radius) or ``(0, 20]`` (separation);
                nothing is changed then.
        """
        r = _length(radius, "wheel radius [m]", MAX_RADIUS)
        s = _length(separation, "wheel separation [m]", MAX_SEPARATION)
        self._radius, self._separation = r, s

    def reset(self) -> None:
        """Back to the world file's geometry."""
        self._radius, self._separation = self.model.radius, self.model.separation

    def wheel_speeds(self, linear: float, angular: float) -> tuple[float, float]:
        """``(left, right)`` wheel speeds [rad/s] for a body velocity: ``linear`` [m/s], ``angular`` [rad/s]."""
        r, half = self._radius, self._separation / 2.0
        return (linear - angular * half) / r, (linear + angular * half) / r

    def body_velocity(self, left: float, right: float) -> tuple[float, float]:
        """``(linear [m/s], angular [rad/s])`` of the body for wheel speeds ``left``, ``right`` [rad/s]."""
        r = self._radius
        return r * (left + right) / 2.0, r * (right - left) / self._separation
