"""The ``ik`` feature: per-world state (robot models, arms, arm motions) and its stepping."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from sigcore.agent.exceptions import ApiError
from sigcore.api.table import ApiEntry
from sigcore.feature import Feature
from sigcore.world.exceptions import FieldError

from .chain import Chain, set_chain_angles
from .config import IkConfig
from .exceptions import InvalidTargetError, MoveError, NoSolutionError
from .model import Vector
from .motion import SETTLED_SPEED, ArmMotion, chain_gravity, duration_for, integral_times
from .robot import RobotIk
from .solver import IkResult, SolverSettings, solve

if TYPE_CHECKING:
    from sigcore.api.deferred import Deferred
    from sigcore.sim import Simulation

SETTLE_ALLOWANCE = 5.0
"""Default move timeout beyond the trajectory's duration [s]."""
MOVE_TOLERANCE = 5e-3
"""A move succeeds when the tip, measured in the simulation, ends within this of the target [m] (or within the
request's tolerance if larger): the servos' accuracy (error after a move: median 0.02-0.2 mm, max 1.2 mm)."""


class IkFeature(Feature):
    """Inverse kinematics (Pinocchio, from each robot's URDF) and arm moves for the robots of a world.

    Config (attributes of ``<plugin name="ik">``): ``agent``, ``max_joint_speed``; see :class:`.config.IkConfig`.
    """

    name = "ik"
    config_model = IkConfig

    @classmethod
    def api_entries(cls) -> list[ApiEntry]:
        """``_ik`` (sig_ros) and ``_ik_solve`` for every robot."""
        from .services import entries

        return entries()

    def __init__(self, sim: Simulation, config: IkConfig) -> None:
        robots = [n for n in sim.entities if sim.entities[n].kind == "robot"]
        names = list(config.agent) or robots
        for n in names:
            if n not in robots:
                raise FieldError("agent", f"'{n}' is not a robot of the world; robots: {', '.join(robots) or 'none'}")
        self.config = config
        self.max_joint_speed = config.max_joint_speed
        self.sim = sim
        self.robots = {n: RobotIk(sim, n) for n in names}
        self.settings = SolverSettings()
        self.motions: dict[tuple[str, str], ArmMotion] = {}
        self.solves = 0
        # called while a motion is driven only (set_every): between motions the core may batch steps
        self._stepping = sim.events.subscribe("step", self._on_step, every=0)

    # ------------------------------------------------------------------ solving
    def robot(self, name: str) -> RobotIk:
        """The IK view of robot ``name``; ``ApiError`` listing the robots with IK otherwise."""
        try:
            return self.robots[name]
        except KeyError:
            raise ApiError(f"IK is not enabled for '{name}'; robots with IK: {', '.join(self.robots)} (set "
                           "<plugin name=\"ik\" agent=...> in the world)") from None

    def solve(self, robot: str, chain: Chain, target_world: pin.SE3, position_only: bool,
              tolerance: float) -> IkResult:
        """Solve for a world-frame target from the current configuration (warm start).

        Raises:
            NoSolutionError: with the residual and the closest configuration.
        """
        r = self.robot(robot)
        target_root = r.base_pose().actInv(target_world)
        result = solve(r.model, chain, r.configuration(), target_root, position_only, tolerance, self.settings)
        self.solves += 1
        if not result.success:
            raise NoSolutionError(chain.name, result.position_error, result.rotation_error, tolerance,
                                   result.angles, position_only, chain.joints)
        return result

    def default_tip(self, robot: str, chain: Chain) -> Vector:
        """Tip position in the root frame with the chain's joints at 0 (clamped to the limits) [m]."""
        r = self.robot(robot)
        q = set_chain_angles(r.model, chain, r.configuration(), chain.clamp(np.zeros(chain.dof)))
        pin.framesForwardKinematics(r.model.model, r.model.data, q)
        return np.asarray(r.model.data.oMf[chain.tip_frame].translation.copy())

    # ------------------------------------------------------------------ moving
    def move(self, robot: str, chain: Chain, goal: Vector, target_world: pin.SE3, timeout: float | None,
             answer: dict[str, object], error_field: str | None = "final_error",
             tolerance: float = MOVE_TOLERANCE) -> Deferred:
        """Start moving ``chain`` to ``goal`` (the solution for ``target_world``).

        The Deferred answers once the arm has settled (:mod:`.motion`), or once, after the trajectory, the tip is
        within ``tolerance`` of the target and every joint is slower than ``SETTLED_SPEED``, or at the timeout.
        It succeeds if the tip's position error measured in the simulation is then within ``tolerance``: with
        ``answer`` plus ``error_field`` (that error [m]). Otherwise it fails with :class:`MoveError` carrying the
        measured joint positions and error.

        Args:
            robot: Robot name.
            chain: The arm.
            goal: The joint solution, shape ``(n,)``.
            target_world: The target in the world frame (re-expressed with the base's pose when measured).
            timeout: Simulated time after which the request is judged as it is [s]; ``None``: the trajectory's
                duration plus 5 s.
            answer: Response fields of a success.
            error_field: Field that gets the measured error on success (``None``: none).
            tolerance: Largest tip position error of a successful move [m].
        """
        from sigcore.api.deferred import Deferred

        r = self.robot(robot)
        old = self.motions.get((robot, chain.name))
        if old is not None and not old.settled:
            old.superseded = True
        angles, _ = r.chain_state(chain)
        now = self.sim.time
        duration = duration_for(angles, goal, self.max_joint_speed)
        if timeout is None:
            timeout = duration + SETTLE_ALLOWANCE
        q_goal = set_chain_angles(r.model, chain, r.configuration(), goal)
        motion = ArmMotion(robot, chain, angles, goal, now, duration, r.kp,
                           integral_times(r.model, chain, q_goal, r.kv), now + timeout)
        self.motions[(robot, chain.name)] = motion
        self._stepping.set_every(1)
        target_root = r.base_pose().actInv(target_world)
        self._drive(r, motion)

        def final_error() -> float:
            target = r.base_pose().act(target_root).translation
            return float(np.linalg.norm(r.tip_position(chain) - target))

        def failed(why: str, error: float) -> MoveError:
            reached, _ = r.chain_state(chain)
            fields = {"joint_names": list(chain.joints), "joint_positions": [float(a) for a in reached],
                      "final_error": error}
            if "solver_error" in answer:
                fields["solver_error"] = answer["solver_error"]
            return MoveError(f"arm '{chain.name}' {why}: tip {error:.4g} m from the target (tolerance "
                             f"{tolerance:g} m)", fields)

        def poll() -> dict[str, object] | None:
            if motion.superseded:
                raise failed(motion.reason, final_error())
            error = final_error()
            if not motion.settled and self.sim.time >= motion.start_time + motion.duration and error <= tolerance:
                _, speeds = r.chain_state(chain)
                motion.settled = float(np.max(np.abs(speeds))) < SETTLED_SPEED
            late = not motion.settled and self.sim.time >= motion.deadline
            if not (motion.settled or late):
                return None
            motion.settled = True  # judged: stop adjusting; the servos hold the last targets
            if error <= tolerance:
                return {**answer, error_field: error} if error_field else dict(answer)
            if late:
                raise failed(f"did not get there within {timeout:g} s (blocked or overloaded?)", error)
            raise failed("stopped short (blocked, overloaded or held at a joint limit?)", error)

        return Deferred(poll, timeout + 1.0, now)

    def _drive(self, r: RobotIk, motion: ArmMotion) -> None:
        angles, speeds = r.chain_state(motion.chain)
        gravity = chain_gravity(r.model, motion.chain, r.configuration(), r.gravity_in_root())
        targets, torques = motion.update(self.sim.time, self.sim.dt, angles, speeds, gravity)
        handle = self.sim.robot(r.name)
        dynamic = self.sim.entities.mode(r.name, "dynamics")
        for joint, target, torque in zip(motion.chain.joints, targets, torques, strict=True):
            handle.set_joint_target(joint, float(target))
            if torque != 0.0 and dynamic:
                handle.add_joint_torque(joint, float(torque))
        motion.holding = bool(np.any(torques != 0.0))

    def _on_step(self, sim: Simulation) -> None:
        driven = False
        for motion in self.motions.values():
            if not motion.superseded and (not motion.settled or motion.holding):
                self._drive(self.robots[motion.robot], motion)
                driven = True
        if not driven:
            self._stepping.set_every(0)

    def reset(self) -> None:
        """The simulation was reset: moves in progress are answered with an error and forgotten."""
        for motion in self.motions.values():
            if not motion.settled:
                motion.superseded, motion.reason = True, "was stopped by a simulation reset"
        self.motions.clear()

    def summary(self) -> dict[str, object]:
        """Number of solves and the arms of each robot."""
        return {"solves": self.solves, "arms": {n: [c.name for c in r.chains] for n, r in self.robots.items()}}


MAX_MAGNITUDE = 1e4
"""Largest magnitude of a target coordinate, quaternion component, tolerance or timeout a request may carry (the
core's position limit, ``sigcore.agent.handle.LIMITS``): beyond it the solver's arithmetic overflows."""


def finite(value: float, field: str) -> float:
    """``value`` if finite and at most ``MAX_MAGNITUDE`` in magnitude, else :class:`InvalidTargetError` naming
    ``field``."""
    if not math.isfinite(value) or abs(value) > MAX_MAGNITUDE:
        raise InvalidTargetError(f"{field} is {value}; valid: a finite number within ±{MAX_MAGNITUDE:g}")
    return value
