"""Moving an arm to an IK solution through its joint servos, over simulated time.

The servo targets follow a minimum-jerk (quintic) joint trajectory from the current angles to the solution,
lasting ``1.875 max|Δq| / max_joint_speed`` (its peak speed is ``max_joint_speed``), at least 0.3 s. Each target
is offset by the gravity torque over the servo gain, ``g(q)/kp`` (Pinocchio, with the base's current tilt), so a
position servo ``kp (target - q)`` holds the arm where it should be instead of sagging (2 cm for sigbot at kp 200).
A target that the joint limits cut short is completed by a joint torque. After the trajectory, a slow integral
term removes what the model does not know (a held object, friction); its time constant is 0.2 s, or
``3 I / kv`` for a joint of inertia ``I`` if longer (stability). The arm has settled when every joint is within
1e-3 rad of the solution and slower than 0.01 rad/s, or when it has stopped moving (every joint slower than
1e-3 rad/s for 0.5 s).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .chain import Chain, set_chain_angles
from .model import RobotModel, Vector

MIN_DURATION = 0.3
"""Shortest trajectory [s]."""
INTEGRAL_TIME = 0.2
"""Shortest time constant of the integral correction after the trajectory [s]."""
INTEGRAL_MARGIN = 3.0
"""The integral time constant of a joint is at least this times ``inertia / kv``: a servo ``kp e - kv qdot`` with an
integral ``kp/Ti ∫e`` on an inertia ``I`` is stable only if ``Ti > I / kv`` (Routh)."""
MAX_BIAS = 0.3
"""Largest integral correction of one joint [rad] or [m]."""
SETTLED_ANGLE = 1e-3
"""Joint error below which the arm may have settled [rad] or [m]."""
SETTLED_SPEED = 1e-2
"""Joint speed below which the arm may have settled [rad/s] or [m/s]."""
STILL_SPEED = 1e-3
STILL_TIME = 0.5
"""The arm has also settled (wherever it is) once every joint has been slower than ``STILL_SPEED`` [rad/s] for
``STILL_TIME`` [s] after the trajectory: the measured error is then reported as it is."""


def min_jerk(s: float) -> float:
    """Minimum-jerk blend ``10 s³ - 15 s⁴ + 6 s⁵`` of ``s`` in [0, 1] (0 and 1 outside)."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


@dataclass
class ArmMotion:
    """One arm travelling to a joint solution.

    Attributes:
        robot: Robot name.
        chain: The arm.
        start: Joint angles at the request, shape ``(n,)``.
        goal: The solution, shape ``(n,)``.
        start_time: Simulation time of the request [s].
        duration: Trajectory duration [s].
        kp: Servo position gain [N m/rad].
        integral_time: Integral time constant of each joint [s], shape ``(n,)`` (inf: no integral).
        deadline: Simulation time after which the request fails [s].
        bias: Integral correction added to the targets, shape ``(n,)``.
        settled: The arm has reached the goal and stopped.
        holding: Extra joint torques are still needed every step (a joint held at a limit against a load).
        still_for: How long every joint has been slower than ``STILL_SPEED`` after the trajectory [s].
        superseded: A newer request moves this arm, or the simulation was reset; the request fails.
        reason: Why it was superseded (for the error message).
    """

    robot: str
    chain: Chain
    start: Vector
    goal: Vector
    start_time: float
    duration: float
    kp: float
    integral_time: Vector
    deadline: float
    bias: Vector = field(default_factory=lambda: np.zeros(0))
    settled: bool = False
    superseded: bool = False
    reason: str = "was given a newer target before it got there"
    holding: bool = False
    still_for: float = 0.0

    def __post_init__(self) -> None:
        if self.bias.shape != self.goal.shape:
            self.bias = np.zeros_like(self.goal)

    def reference(self, time: float) -> Vector:
        """Trajectory angles at simulation time ``time`` [s]."""
        blend = min_jerk((time - self.start_time) / self.duration)
        return self.start + (self.goal - self.start) * blend

    def update(self, time: float, dt: float, angles: Vector, speeds: Vector,
               gravity: Callable[[Vector], Vector]) -> tuple[Vector, Vector]:
        """Servo targets and extra joint torques [N m] for the next step; marks the motion settled when it is.

        A target is clamped to the joint's limits; what the clamp cuts off (a joint held at a limit against a
        load pulling it inwards) is applied as a joint torque ``kp * (wanted - clamped)`` instead.

        Args:
            time: Simulation time [s].
            dt: Timestep [s].
            angles: Measured chain angles, shape ``(n,)``.
            speeds: Measured chain joint speeds, shape ``(n,)``.
            gravity: Holding torques of the chain joints at given chain angles [N m], shape ``(n,)``.
        """
        ref = self.reference(time)
        if time >= self.start_time + self.duration:
            error = self.goal - angles
            self.bias = np.clip(self.bias + error * (dt / self.integral_time), -MAX_BIAS, MAX_BIAS)
            speed = float(np.max(np.abs(speeds)))
            self.still_for = self.still_for + dt if speed < STILL_SPEED else 0.0
            if (float(np.max(np.abs(error))) < SETTLED_ANGLE and speed < SETTLED_SPEED) or self.still_for >= STILL_TIME:
                self.settled = True
        wanted = ref + gravity(ref) / self.kp + self.bias
        targets = self.chain.clamp(wanted)
        return targets, self.kp * (wanted - targets)


def duration_for(start: Vector, goal: Vector, max_speed: float) -> float:
    """Duration [s] of a minimum-jerk move whose fastest joint peaks at ``max_speed`` [rad/s]."""
    return max(MIN_DURATION, 1.875 * float(np.max(np.abs(goal - start))) / max_speed)


def integral_times(robot: RobotModel, chain: Chain, q: Vector, kv: float) -> Vector:
    """Integral time constant of each chain joint [s] for configuration ``q``: ``INTEGRAL_MARGIN * I / kv`` with
    the joint's inertia ``I`` (the diagonal of the mass matrix), at least ``INTEGRAL_TIME``; inf if ``kv`` is 0."""
    if kv <= 0:
        return np.full(chain.dof, np.inf)
    inertia = np.diag(pin.crba(robot.model, robot.data, q))[list(chain.idx_v)]
    return np.maximum(INTEGRAL_TIME, INTEGRAL_MARGIN * inertia / kv)


def chain_gravity(robot: RobotModel, chain: Chain, q: Vector, gravity_in_root: Vector) -> Callable[[Vector], Vector]:
    """``f(angles)``: holding torques of the chain's joints with the rest of the robot as in ``q``."""
    idx_v = list(chain.idx_v)

    def f(angles: Vector) -> Vector:
        return robot.gravity(set_chain_angles(robot, chain, q, angles), gravity_in_root)[idx_v]

    return f
