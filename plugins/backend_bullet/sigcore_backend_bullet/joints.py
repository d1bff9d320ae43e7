"""Joint angles, velocities, servo targets and torques of :class:`~.backend.BulletBackend`'s robots, and the
postures of its persons (a mixin; a person's joints have no motor, see :mod:`.base`)."""

from __future__ import annotations

import numpy as np
import pybullet as pb

from sigcore.backend import Array, passive_joint
from sigcore.errors import BackendRefusal

from .base import BulletBase
from .layout import EntityIndex, JointIndex


class BulletJoints(BulletBase):
    """Reading joints and commanding them through their motors (see :mod:`.servo`)."""

    def get_joint_angle(self, entity: str, joint: str) -> float:
        """``getJointState`` position [rad] or [m]; a person's: its posture (a mannequin's joints are fixed)."""
        e = self._entity(entity)
        j = e.joint(joint)
        if e.kind == "human":
            return self._posture[e.name][list(e.joints).index(joint)]
        return float(pb.getJointState(e.body, j.index, physicsClientId=self.client)[0])

    def set_joint_angle(self, entity: str, joint: str, angle: float) -> None:
        """``resetJointState`` (velocity 0); an arm joint's position servo then holds ``angle``. A person keeps
        it: held, its joints are put back at it after every step; a mannequin gets a new rigid body."""
        e = self._entity(entity)
        j = e.joint(joint)
        if e.kind == "human":
            posture, k = self._posture[e.name], list(e.joints).index(joint)
            if e.rigid and posture[k] == angle:
                return  # a mannequin's body is built again only for a new posture
            posture[k] = float(angle)
            if e.rigid:
                self._rebuild_human(e, rigid=True)
            else:
                pb.resetJointState(e.body, j.index, angle, 0.0, physicsClientId=self.client)
            self._tick += 1
            return
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
        e, j = self._motor(entity, joint)
        if j.wheel:
            arms = [n for n, x in e.joints.items() if not x.wheel]
            raise BackendRefusal(f"joint '{joint}' of '{entity}' is a drive wheel, always velocity-controlled: "
                               f"use set_joint_velocity; joints with position control: "
                               f"{', '.join(arms) or 'none'}")
        self._position_servo(e, j, angle)

    def set_joint_velocity(self, entity: str, joint: str, velocity: float,
                           max_torque: float | None = None) -> None:
        """``VELOCITY_CONTROL`` at ``velocity`` with force ``max_torque`` (default: the drive's or the gains')."""
        e, j = self._motor(entity, joint)
        torque = j.max_torque if max_torque is None else max_torque
        if not j.wheel:
            self._servos[e.name].release(j.index)
        pb.setJointMotorControl2(e.body, j.index, pb.VELOCITY_CONTROL, targetVelocity=velocity, force=torque,
                                 physicsClientId=self.client)

    def add_joint_torque(self, entity: str, joint: str, torque: float) -> None:
        """``TORQUE_CONTROL`` for the next step (on top of the joint's motor)."""
        e, j = self._motor(entity, joint)
        self._wake()
        pb.setJointMotorControl2(e.body, j.index, pb.TORQUE_CONTROL, force=torque, physicsClientId=self.client)

    def _motor(self, entity: str, joint: str) -> tuple[EntityIndex, JointIndex]:
        """The entity and joint to drive.

        Raises:
            BackendRefusal: no such joint (listing the valid ones), or a joint of a person (it has no motor).
        """
        e = self._entity(entity)
        j = e.joint(joint)
        if e.kind == "human":
            raise BackendRefusal(passive_joint(entity, joint))
        return e, j

    def get_joint_position(self, entity: str, joint: str) -> Array:
        """World position [m] of the joint anchor: the child link's URDF frame origin."""
        e = self._entity(entity)
        return np.array(self._frame(e, e.joint(joint).index)[0], dtype=np.float64)
