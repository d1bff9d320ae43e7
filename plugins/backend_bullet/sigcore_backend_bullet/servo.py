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
``setJointMotorControlArray`` per robot per step while the arm moves.

A bank whose joints have all been still (:data:`STILL_STEP`) for :data:`QUIET_STEPS` steps
goes quiet: its motors become brakes (target speed 0) whose force limit is :data:`BRAKE_MARGIN` times the
largest torque they applied in the last two steps (the load, through the ripple) plus :data:`BRAKE_SLACK`, and
the bank only looks at its joints every :data:`CHECK_EVERY` steps. A joint that has moved by
:data:`STILL_MOVE`, or whose brake torque has changed by :data:`TORQUE_CHANGE` of what it was at the first look
(plus ``BRAKE_SLACK``) -- the load changed --, a new target or mode, and any write of the backend that can
disturb the arm (forces, poses, grasps, masses, modes) wake it. An arm at rest thus costs about a tenth of the
update; a disturbance is seen within ``CHECK_EVERY`` steps, during which the arm holds rigidly up to the brake's
limit instead of giving as the spring would.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pybullet as pb

QUIET_STEPS = 10
"""Steps of stillness after which a bank goes quiet."""
CHECK_EVERY = 5
"""A quiet bank looks at its joints every this many steps."""
STILL_STEP = 1e-6
"""A joint is still when it is within this [rad] or [m] of where it was two steps before (a loaded joint at rest
oscillates with a period of two steps: about ±1e-4 rad, ±0.1 rad/s, on a light arm; a joint closing its error
with the servo's time constant of ``kv / kp`` = 0.05 s is this still 1e-5 rad from its rest)."""
STILL_MOVE = 1e-4
"""How far [rad] or [m] a quiet joint may move before its bank wakes."""
BRAKE_MARGIN = 1.2
"""A quiet joint's brake holds this many times its load."""
BRAKE_SLACK = 0.02
"""Torque [N m] added to every brake's limit and to the tolerance of the load check."""
TORQUE_CHANGE = 0.1
"""Relative change of a brake's torque that wakes its bank."""


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
    _still: int = 0
    _quiet: bool = False
    _countdown: int = 0
    _rest: list[float] = field(default_factory=list)
    _before: list[float] = field(default_factory=list)
    _torque: list[float] = field(default_factory=list)
    _load: list[float] | None = None

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
        self.wake()

    def wake(self) -> None:
        """Update the motors from the next step on (a target, a mode or the world changed)."""
        self._quiet = False
        self._still = 0

    def update(self, client: int) -> None:
        """Set each position motor's target speed and force limit from the current state (about 6 us for 16
        joints; a quiet bank only looks every :data:`CHECK_EVERY` steps)."""
        if not self._order:
            return
        if self._quiet:
            self._countdown -= 1
            if self._countdown > 0:
                return
            self._countdown = CHECK_EVERY
            states = pb.getJointStates(self.body, self._order, physicsClientId=client)
            if all(-STILL_MOVE < q - rest < STILL_MOVE for (q, _, _, _), rest in zip(states, self._rest, strict=True)):
                if self._load is None:
                    self._load = [tau for _, _, _, tau in states]
                    return
                if all(abs(tau - load) <= TORQUE_CHANGE * abs(load) + BRAKE_SLACK
                       for (_, _, _, tau), load in zip(states, self._load, strict=True)):
                    return
            self.wake()
        else:
            states = pb.getJointStates(self.body, self._order, physicsClientId=client)
        speeds = []
        forces = []
        for (q, qdot, _, _), (target, kp, kv, gain, limit) in zip(states, self._rows, strict=True):
            error = target - q
            speeds.append(gain * error)
            tau = kp * error - kv * qdot
            tau = -tau if tau < 0.0 else tau
            forces.append(limit if tau > limit else tau)
        torque = [tau for _, _, _, tau in states]
        angles = [q for q, _, _, _ in states]
        if len(self._before) == len(angles) and all(
                -STILL_STEP < q - q2 < STILL_STEP for q, q2 in zip(angles, self._before, strict=True)):
            self._still += 1
        else:
            self._still = 0
        self._before, self._rest = self._rest, angles
        if self._still >= QUIET_STEPS:  # brakes holding the load: no ripple, no drift
            speeds = [0.0] * len(states)
            forces = [min(BRAKE_MARGIN * max(abs(a), abs(b)) + BRAKE_SLACK, row[4])
                      for a, b, row in zip(torque, self._torque, self._rows, strict=True)]
            self._quiet, self._countdown, self._load = True, CHECK_EVERY, None
        self._torque = torque
        pb.setJointMotorControlArray(self.body, self._order, pb.VELOCITY_CONTROL, targetVelocities=speeds,
                                     forces=forces, physicsClientId=client)
