"""Joint drives: a switchable position/velocity servo for arm joints, a velocity motor for drive wheels.

Why not one proportional servo for everything. MuJoCo 4.0 integrates an actuator whose force is clamped by its
``forcerange`` explicitly (a saturated actuator contributes no implicit damping). A stiff velocity servo,
``force = k (v_target - qdot)`` clamped to the torque limit, on a light joint then overshoots by
``max_torque * dt / inertia`` in one step and chatters between its limits (a 0.0025 kg m^2 wheel with 20 N m
at 2 ms: +-16 rad/s); a gain low enough not to (``inertia / dt``) leaves a large velocity error under load (a
cylinder wheel scrubbing while turning in place lost 19 % of its speed). Hence:

* **Arm joints** (every joint that is not a drive wheel) have MuJoCo's integrated-velocity servo: an
  ``integrator`` actuator whose activation ``act`` is the position target, ``force = kp (act - q) - kv qdot``
  with the world's ``<gains>``, clamped to ``max_torque`` (and to the URDF ``effort``, which MuJoCo imports as
  the joint's ``actuatorfrcrange``); ``act`` is limited to the joint's range. *Position mode* writes the
  target into ``act`` and ``ctrl = 0``. *Velocity mode* starts ``act`` at the current angle and sets ``ctrl``
  = the target velocity, so the target moves at that velocity and the joint follows it: the velocity is
  tracked exactly under a constant load (gravity), like a PI velocity loop, and the target stops at the joint
  limit (bounded wind-up). Switching mode rewrites no model parameter, only ``act`` and ``ctrl`` (and
  ``actuator_forcerange`` when a velocity call gives its own torque limit).
* **Drive wheels** have a velocity *motor* solved by the constraint solver, like ODE's and Bullet's joint
  motors: a fixed tendon ``q_wheel - q_motor`` with ``frictionloss = max_torque``, where ``q_motor`` is a
  hidden hinge (no geometry, armature 1e9) that spins at the target velocity and is not measurably slowed by
  the reaction. Each step the solver finds the torque, within the limit, that makes the wheel turn at the
  motor's speed: exact tracking, no overshoot, no chatter, a brake holding the wheel at velocity 0.
  ``set_joint_velocity`` writes the motor's ``qvel`` and, for a new limit, ``tendon_frictionloss``. The world
  uses ``noslip_iterations`` so that this and the contact friction do not creep.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

POSITION = "position"
VELOCITY = "velocity"

MOTOR_ARMATURE = 1e9
"""Armature [kg m^2] of a wheel's hidden motor joint: a 20 N m reaction slows it by 4e-11 rad/s per 2 ms
step."""


def motor_name(robot: str, joint: str) -> str:
    """Name of the hidden motor body, joint and tendon of a drive wheel (no entity prefix: not a part)."""
    return f"motor:{robot}:{joint}"


@dataclass
class ArmServo:
    """The integrator actuator of an arm joint.

    Attributes:
        actuator: Actuator id.
        act: Address of its activation (the position target) in ``data.act``.
        qpos: The joint's qpos address.
        default_torque: Torque limit [N m] of the world's ``<gains>``.
        mode: ``"position"`` or ``"velocity"``.
        torque: Current torque limit [N m].
    """

    actuator: int
    act: int
    qpos: int
    default_torque: float
    mode: str = POSITION
    torque: float = 0.0
    wheel: bool = False

    def hold(self, model: mujoco.MjModel, data: mujoco.MjData, angle: float) -> None:
        """Position mode towards ``angle`` [rad] or [m]."""
        if self.torque != self.default_torque:
            self._limit(model, self.default_torque)
        data.act[self.act] = angle
        data.ctrl[self.actuator] = 0.0
        self.mode = POSITION

    def drive(self, model: mujoco.MjModel, data: mujoco.MjData, velocity: float,
              max_torque: float | None) -> None:
        """Velocity mode at ``velocity`` [rad/s], limited to ``max_torque`` [N m] (``None``: the default)."""
        torque = self.default_torque if max_torque is None else max_torque
        if torque != self.torque:
            self._limit(model, torque)
        if self.mode != VELOCITY:
            data.act[self.act] = data.qpos[self.qpos]
            self.mode = VELOCITY
        data.ctrl[self.actuator] = velocity

    def restart(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Initial state on a freshly restored model: holding the joint's ``qpos0`` angle."""
        self.mode, self.torque = POSITION, self.default_torque
        data.ctrl[self.actuator] = 0.0
        data.act[self.act] = model.qpos0[self.qpos]

    def _limit(self, model: mujoco.MjModel, torque: float) -> None:
        model.actuator_forcerange[self.actuator] = (-torque, torque)
        self.torque = torque


@dataclass
class WheelMotor:
    """The velocity motor of a drive wheel: a hidden motor joint coupled to the wheel by a friction tendon.

    Attributes:
        motor_dof: Dof address of the hidden motor joint (its ``qvel`` is the target velocity).
        tendon: Tendon id (its ``frictionloss`` is the torque limit).
        default_torque: The drive's ``max_torque`` [N m].
        torque: Current torque limit [N m].
    """

    motor_dof: int
    tendon: int
    default_torque: float
    torque: float = 0.0
    mode: str = VELOCITY
    wheel: bool = True

    def drive(self, model: mujoco.MjModel, data: mujoco.MjData, velocity: float,
              max_torque: float | None) -> None:
        """Turn the wheel at ``velocity`` [rad/s] with at most ``max_torque`` [N m] (``None``: the
        default)."""
        torque = self.default_torque if max_torque is None else max_torque
        if torque != self.torque:
            model.tendon_frictionloss[self.tendon] = torque
            self.torque = torque
        data.qvel[self.motor_dof] = velocity

    def restart(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Initial state on a freshly restored model: braking at velocity 0 with the default torque."""
        self.torque = float(model.tendon_frictionloss[self.tendon])
        data.qvel[self.motor_dof] = 0.0


Drive = ArmServo | WheelMotor
