"""Joint angles, velocities, servo targets and torques of :class:`~.backend.BulletBackend`'s robots (a mixin)."""

from __future__ import annotations

import numpy as np
import pybullet as pb

from sigcore.backend import Array
from sigcore.errors import BackendRefusal

from .base import BulletBase


class BulletJoints(BulletBase):
    """Reading joints and commanding them through their motors (see :mod:`.servo`)."""

    def get_joint_angle(self, entity: str, joint: str) -> float:
        """``getJointState`` position [rad] or [m]."""
        e = self._entity(entity)
        return float(pb.getJointState(e.body, e.joint(joint).index, physicsClientId=self.client)[0])

    def set_joint_angle(self, entity: str, joint: str, angle: float) -> None:
        """``resetJointState`` (velocity 0); an arm joint's position servo then holds ``angle``."""
        e = self._entity(entity)
        j = e.joint(joint)
        pb.resetJointState(e.body, j.index, angle, 0.0, physicsClientId=self.client)
        if not j.wheel:
            self._position_servo(e, j, angle)
        if e.name in self._held:
            self._hold(e)
        self._tick += 1

    def get_joint_velocity(self, entity: str, joint: str) -> float:
        """``getJointState`` velocity [rad/s] or [m/s]."""
        e = self._entity(entity)
        return float(pb.getJointState(e.body, e.joint(joint).index, physicsClientId=self.client)[1])

    def set_joint_target(self, entity: str, joint: str, angle: float) -> None:
        """Position servo towards ``angle``.

        Raises:
            BackendRefusal: the joint is a drive wheel (always a velocity servo).
        """
        e = self._entity(entity)
        j = e.joint(joint)
        if j.wheel:
            arms = [n for n, x in e.joints.items() if not x.wheel]
            raise BackendRefusal(f"joint '{joint}' of '{entity}' is a drive wheel, always velocity-controlled: "
                               f"use set_joint_velocity; joints with position control: "
                               f"{', '.join(arms) or 'none'}")
        self._position_servo(e, j, angle)

    def set_joint_velocity(self, entity: str, joint: str, velocity: float,
                           max_torque: float | None = None) -> None:
        """``VELOCITY_CONTROL`` at ``velocity`` with force ``max_torque`` (default: the drive's or the gains')."""
        e = self._entity(entity)
        j = e.joint(joint)
        torque = j.max_torque if max_torque is None else max_torque
        if not j.wheel:
            self._servos[e.name].release(j.index)
        pb.setJointMotorControl2(e.body, j.index, pb.VELOCITY_CONTROL, targetVelocity=velocity, force=torque,
                                 physicsClientId=self.client)

    def add_joint_torque(self, entity: str, joint: str, torque: float) -> None:
        """``TORQUE_CONTROL`` for the next step (on top of the joint's motor)."""
        self._wake()
        e = self._entity(entity)
        pb.setJointMotorControl2(e.body, e.joint(joint).index, pb.TORQUE_CONTROL, force=torque,
                                 physicsClientId=self.client)

    def get_joint_position(self, entity: str, joint: str) -> Array:
        """World position [m] of the joint anchor: the child link's URDF frame origin."""
        e = self._entity(entity)
        return np.array(self._frame(e, e.joint(joint).index)[0], dtype=np.float64)
