"""Wheel odometry of a differential-drive robot (REP-105 ``odom -> base_link``), integrated every step."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..backend import Backend
from ..geometry import quat_yaw
from .drive import DriveState


@dataclass
class OdometryState:
    """Pose of ``base_link`` in ``odom`` and body velocities.

    Attributes:
        x: [m] in the odom frame.
        y: [m] in the odom frame.
        yaw: [rad] about z.
        v: Forward velocity [m/s].
        w: Yaw rate [rad/s].
        stamp: Simulation time [s].
    """

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    v: float = 0.0
    w: float = 0.0
    stamp: float = 0.0


class WheelOdometry:
    """Integrates the wheel joint speeds of a differential drive (midpoint rule), optionally with noise.

    The odom frame starts at the robot's initial pose (projected to the ground plane): at time 0, ``odom`` and
    the world coincide with the robot's start. ``noise`` scales a Gaussian error on each wheel's speed [fraction].
    The wheel radius and separation are read from the robot's :class:`~sigcore.sim.drive.DriveState` at each step.
    """

    def __init__(self, robot: str, drive: DriveState, backend: Backend, dt: float, noise: float = 0.0,
                 seed: int = 0) -> None:
        self.robot = robot
        self.drive = drive
        self.dt = dt
        self.noise = noise
        self._rng = np.random.default_rng(seed)
        pos, quat = backend.get_pose(robot)
        self.origin = (float(pos[0]), float(pos[1]), quat_yaw(quat))
        self.state = OdometryState()

    def reset(self) -> None:
        """Back to the origin (after a simulation reset)."""
        self.state = OdometryState(stamp=self.state.stamp)

    def update(self, backend: Backend, time: float) -> OdometryState:
        """Advance by one step from the current wheel speeds."""
        d = self.drive
        wl = backend.get_joint_velocity(self.robot, d.left)
        wr = backend.get_joint_velocity(self.robot, d.right)
        if self.noise > 0:
            wl *= 1.0 + self._rng.normal(0.0, self.noise)
            wr *= 1.0 + self._rng.normal(0.0, self.noise)
        v, w = d.body_velocity(wl, wr)  # with the geometry now in use (``_setWheel`` may have changed it)
        if not (math.isfinite(v) and math.isfinite(w)):
            v = w = 0.0  # the physics diverged (a wheel speed is infinite): hold the pose, never end the run
        s = self.state
        mid = s.yaw + w * self.dt / 2.0
        s.x += v * math.cos(mid) * self.dt
        s.y += v * math.sin(mid) * self.dt
        s.yaw = math.atan2(math.sin(s.yaw + w * self.dt), math.cos(s.yaw + w * self.dt))
        s.v, s.w, s.stamp = v, w, time
        return s
