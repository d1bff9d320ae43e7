"""Joint angles, velocities, servo targets and torques of :class:`~.backend.MujocoBackend`'s robots and people (a
mixin; a person's joints have no actuator: only their angles are set)."""

from __future__ import annotations

from collections.abc import Mapping

from sigcore.backend import Array, passive_joint
from sigcore.errors import BackendRefusal

from .base import MujocoBase
from .servo import ArmServo


class MujocoJoints(MujocoBase):
    """Reading joints and commanding them through their servos (see :mod:`.servo`)."""

    def get_joint_angle(self, entity: str, joint: str) -> float:
        """``qpos`` of the joint [rad] or [m]."""
        return float(self.data.qpos[self._entity(entity).joint(joint).qpos])

    def set_joint_angle(self, entity: str, joint: str, angle: float) -> None:
        """Set ``qpos`` (and zero ``qvel``) of the joint; an arm joint's servo then holds ``angle``."""
        e = self._entity(entity)
        j = e.joint(joint)
        self.data.qpos[j.qpos] = angle
        self.data.qvel[j.dof] = 0.0
        if isinstance(j.servo, ArmServo):
            j.servo.hold(self.model, self.data, angle)
        if j.lock >= 0:  # a person's joint: its lock (active while the person is dynamic) holds the new angle
            self.model.eq_data[j.lock, 0] = angle
        self._update_hold(e)
        self._tick += 1

    def set_joint_angles(self, entity: str, angles: Mapping[str, float]) -> None:
        """Every ``joint: angle`` at once (a person's posture at one step): one update of the held values."""
        e = self._entity(entity)
        for joint, angle in angles.items():
            j = e.joint(joint)
            self.data.qpos[j.qpos] = angle
            self.data.qvel[j.dof] = 0.0
            if isinstance(j.servo, ArmServo):
                j.servo.hold(self.model, self.data, angle)
            if j.lock >= 0:
                self.model.eq_data[j.lock, 0] = angle
        self._update_hold(e)
        self._tick += 1

    def get_joint_velocity(self, entity: str, joint: str) -> float:
        """``qvel`` of the joint [rad/s] or [m/s]."""
        return float(self.data.qvel[self._entity(entity).joint(joint).dof])

    def set_joint_target(self, entity: str, joint: str, angle: float) -> None:
        """Position servo towards ``angle``.

        Raises:
            BackendRefusal: the joint is a drive wheel (always a velocity servo).
        """
        e = self._entity(entity)
        j = e.joint(joint)
        if j.servo is None:
            raise BackendRefusal(passive_joint(entity, joint))
        if not isinstance(j.servo, ArmServo):
            arms = [n for n, x in e.joints.items() if isinstance(x.servo, ArmServo)]
            raise BackendRefusal(f"joint '{joint}' of '{entity}' is a drive wheel, always velocity-controlled: "
                               f"use set_joint_velocity; joints with position control: "
                               f"{', '.join(arms) or 'none'}")
        j.servo.hold(self.model, self.data, angle)

    def set_joint_velocity(self, entity: str, joint: str, velocity: float,
                           max_torque: float | None = None) -> None:
        """Velocity mode at ``velocity``, limited to ``max_torque`` (default: the drive's or the gains')."""
        j = self._entity(entity).joint(joint)
        if j.servo is None:
            raise BackendRefusal(passive_joint(entity, joint))
        j.servo.drive(self.model, self.data, velocity, max_torque)

    def add_joint_torque(self, entity: str, joint: str, torque: float) -> None:
        """Add to ``qfrc_applied`` of the joint's dof for the next step."""
        j = self._entity(entity).joint(joint)
        if j.servo is None:
            raise BackendRefusal(passive_joint(entity, joint))
        self.data.qfrc_applied[j.dof] += torque
        self._applied = self._post = True

    def get_joint_position(self, entity: str, joint: str) -> Array:
        """World position [m] of the joint anchor (``xanchor``)."""
        j = self._entity(entity).joint(joint)
        self._sync()
        return self.data.xanchor[j.jnt].copy()
