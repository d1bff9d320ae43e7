"""A waypoint follower for a differential-drive robot on its ground-truth pose (no planning: straight lines)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from sigcore.agent.robot import RobotObj
from sigcore.geometry import quat_yaw


def wrap(angle: float) -> float:
    """``angle`` [rad] in (-π, π]."""
    return math.atan2(math.sin(angle), math.cos(angle))


@dataclass
class DriveLimits:
    """How the follower may move the base.

    Attributes:
        speed: Top linear speed [m/s].
        turn: Top angular speed [rad/s].
        accel: Linear acceleration and braking [m/s²] (the robot is tall: brake gently).
        turn_accel: Angular acceleration [rad/s²].
        tolerance: Position reached within this [m].
        yaw_tolerance: Heading reached within this [rad].
    """

    speed: float = 0.8
    turn: float = 1.5
    accel: float = 1.0
    turn_accel: float = 3.0
    tolerance: float = 0.01
    yaw_tolerance: float = 0.01


class Follower:
    """Commands ``set_base_velocity`` once per control period towards a point or a heading."""

    def __init__(self, robot: RobotObj, period: float, limits: DriveLimits | None = None) -> None:
        self.robot, self.period = robot, period
        self.limits = limits or DriveLimits()
        self.v = 0.0
        self.w = 0.0

    def pose(self) -> tuple[float, float, float]:
        """``(x, y, yaw)`` of the base [m, m, rad]."""
        p = self.robot.position()
        return float(p[0]), float(p[1]), quat_yaw(self.robot.rotation())

    def _command(self, v: float, w: float) -> None:
        lim, dt = self.limits, self.period
        self.v += max(-lim.accel * dt, min(lim.accel * dt, v - self.v))
        self.w += max(-lim.turn_accel * dt, min(lim.turn_accel * dt, w - self.w))
        self.robot.set_base_velocity(self.v, self.w)

    def stop(self) -> bool:
        """Brake; True once stopped."""
        self._command(0.0, 0.0)
        return self.v == 0.0 and self.w == 0.0

    def turn_to(self, yaw: float) -> bool:
        """Turn in place towards heading ``yaw`` [rad]; True once there and stopped."""
        err = wrap(yaw - self.pose()[2])
        lim = self.limits
        if abs(err) < lim.yaw_tolerance:
            return self.stop()
        w = math.copysign(min(lim.turn, math.sqrt(2 * lim.turn_accel * abs(err)) * 0.8, 4.0 * abs(err)), err)
        self._command(0.0, w)
        return False

    def go_to(self, x: float, y: float, backwards: bool = False) -> bool:
        """Drive to (x, y) [m] forwards (or backwards), turning in place first if the heading is far off; True
        once there and stopped."""
        px, py, yaw = self.pose()
        dx, dy = x - px, y - py
        dist = math.hypot(dx, dy)
        lim = self.limits
        if dist < lim.tolerance:
            return self.stop()
        heading = math.atan2(dy, dx) + (math.pi if backwards else 0.0)
        err = wrap(heading - yaw)
        if abs(err) > 0.3 and dist > 0.05:
            if abs(self.v) > 0.02:
                self._command(0.0, self.w)
            else:
                w = math.copysign(min(lim.turn, 4.0 * abs(err)), err)
                self._command(0.0, w)
            return False
        along = dist * math.cos(err)
        speed = min(lim.speed, math.sqrt(2 * lim.accel * max(along, 0.0)) * 0.8, 2.0 * dist)
        w = max(-lim.turn, min(lim.turn, 3.0 * err)) if dist > 0.05 else 0.0
        self._command(-speed if backwards else speed, w)
        return False
