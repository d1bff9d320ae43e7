"""Arm-joint position servos with the world's gains: PyBullet's constraint motor, capped by the PD torque.

A PyBullet joint motor is a velocity constraint solved with the contacts: it applies whatever torque, up to its
``force``, makes the joint turn at its target velocity. A position servo made of it (``VELOCITY_CONTROL`` at
``(kp / kv) (target - q)``, the first-order approach with the servo's time constant ``kv / kp``) with
``force = max_torque`` is *stiff*: a load below the torque limit (gravity, a push, ``add_joint_torque``) does not
deflect the joint at all, unlike the spring-damper ``tau = kp (target - q) - kv qdot`` that the world's ``<gains>``
describe (and MuJoCo's servo implements).

So before every step each motor's target velocity is set to ``(kp / kv) (target - q)`` and its force limit to
``|kp (target - q) - kv qdot|`` (at most ``max_torque``): the constraint still decides the torque, so the joint
never overshoots the first-order approach (stable for any link inertia, which an explicit PD torque on a light
finger is not), but it pushes no harder than the spring-damper would. Under a steady load the joint settles where
``kp e`` balances the load: the sag ``load / kp`` of MuJoCo (0.8069 rad for a 0.8 rad target on both engines in
the conformance bot). The price: the explicit ``kv qdot`` in the limit leaves a velocity ripple of about
±0.01 rad/s (±2e-5 rad) on a loaded joint at rest. Cost: one ``getJointStates`` and one
``setJointMotorControlArray`` per robot per step.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pybullet as pb


@dataclass
class ServoBank:
    """The position-mode arm joints of one robot.

    Attributes:
        body: PyBullet body id.
        targets: Target angle [rad] or [m] of each joint index in position mode.
        kp: Position gain [N m/rad] of each joint index.
        kv: Damping [N m s/rad] of each joint index.
        gain: Speed [1/s] at which each joint index closes its error (``kp / kv``).
        limit: Torque limit [N m] of each joint index.
    """

    body: int
    targets: dict[int, float] = field(default_factory=dict)
    kp: dict[int, float] = field(default_factory=dict)
    kv: dict[int, float] = field(default_factory=dict)
    gain: dict[int, float] = field(default_factory=dict)
    limit: dict[int, float] = field(default_factory=dict)
    _order: list[int] = field(default_factory=list)
    _rows: list[tuple[float, float, float, float, float]] = field(default_factory=list)

    def add(self, index: int, kp: float, kv: float, gain: float, limit: float) -> None:
        """Declare an arm joint (in no mode yet)."""
        self.kp[index], self.kv[index], self.gain[index], self.limit[index] = kp, kv, gain, limit

    def hold(self, index: int, angle: float) -> None:
        """Position mode towards ``angle``."""
        self.targets[index] = angle
        self._reorder()

    def release(self, index: int) -> None:
        """Leave position mode (the joint is now velocity-controlled)."""
        if self.targets.pop(index, None) is not None:
            self._reorder()

    def _reorder(self) -> None:
        self._order = sorted(self.targets)
        self._rows = [(self.targets[j], self.kp[j], self.kv[j], self.gain[j], self.limit[j]) for j in self._order]

    def update(self, client: int) -> None:
        """Set each position motor's target speed and force limit from the current state (about 6 us for 16
        joints)."""
        if not self._order:
            return
        states = pb.getJointStates(self.body, self._order, physicsClientId=client)
        speeds = []
        forces = []
        for (q, qdot, _, _), (target, kp, kv, gain, limit) in zip(states, self._rows, strict=True):
            error = target - q
            speeds.append(gain * error)
            tau = kp * error - kv * qdot
            tau = -tau if tau < 0.0 else tau
            forces.append(limit if tau > limit else tau)
        pb.setJointMotorControlArray(self.body, self._order, pb.VELOCITY_CONTROL, targetVelocities=speeds,
                                     forces=forces, physicsClientId=client)
