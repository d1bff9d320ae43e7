"""The ``ik`` feature: per-world state (robot models, arms, arm motions) and its stepping."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from sigcore.agent.exceptions import ApiError
from sigcore.api.table import ApiEntry
from sigcore.feature import Feature

from .chain import Chain, set_chain_angles
from .exceptions import InvalidTargetError, MoveError, UnreachableError
from .model import Vector
from .motion import ArmMotion, chain_gravity, duration_for, integral_times
from .robot import RobotIk
from .solver import IkResult, SolverSettings, solve

if TYPE_CHECKING:
    from sigcore.api.deferred import Deferred
    from sigcore.sim import Simulation

SETTLE_ALLOWANCE = 5.0
"""Default move timeout beyond the trajectory's duration [s]."""

CONFIG = {"agent": "robots with IK, space-separated (default: every robot)",
          "max_joint_speed": "peak joint speed of a move in [rad/s] (default 1.0)"}


class IkFeature(Feature):
    """Inverse kinematics (Pinocchio, from each robot's URDF) and arm moves for the robots of a world.

    Config (attributes of ``<plugin name="ik">``): ``agent``, ``max_joint_speed``; see :data:`CONFIG`.
    """

    name = "ik"

    @classmethod
    def api_entries(cls) -> list[ApiEntry]:
        """``_ik`` (sig_ros) and ``_ik_solve`` for every robot."""
        from .services import entries

        return entries()

    def __init__(self, sim: Simulation, config: dict[str, str]) -> None:
        unknown = sorted(set(config) - set(CONFIG))
        if unknown:
            raise ValueError(f"unknown attribute '{unknown[0]}'; valid: {', '.join(CONFIG)}")
        robots = [n for n in sim.agents if sim.agents[n].kind == "robot"]
        names = config.get("agent", "").replace(",", " ").split() or robots
        for n in names:
            if n not in robots:
                raise ValueError(f"agent: '{n}' is not a robot of the world; robots: {', '.join(robots) or 'none'}")
        try:
            self.max_joint_speed = float(config.get("max_joint_speed", "1.0"))
        except ValueError:
            raise ValueError(f"max_joint_speed: '{config['max_joint_speed']}' is not a number; valid: a speed "
                             "in [rad/s] > 0, e.g. 1.0") from None
        if not (math.isfinite(self.max_joint_speed) and self.max_joint_speed > 0):
            raise ValueError(f"max_joint_speed: {self.max_joint_speed} is not > 0 [rad/s]")
        self.sim = sim
        self.robots = {n: RobotIk(sim, n) for n in names}
        self.settings = SolverSettings()
        self.motions: dict[tuple[str, str], ArmMotion] = {}
        self.solves = 0
        sim.add_step_observer(self._on_step)

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
            UnreachableError: with the residual and the closest configuration.
        """
        r = self.robot(robot)
        target_root = r.base_pose().actInv(target_world)
        result = solve(r.model, chain, r.configuration(), target_root, position_only, tolerance, self.settings)
        self.solves += 1
        if not result.success:
            raise UnreachableError(chain.name, result.position_error, result.rotation_error, tolerance,
                                   result.angles, position_only)
        return result

    def default_tip(self, robot: str, chain: Chain) -> Vector:
        """Tip position in the root frame with the chain's joints at 0 (clamped to the limits) [m]."""
        r = self.robot(robot)
        q = set_chain_angles(r.model, chain, r.configuration(), chain.clamp(np.zeros(chain.dof)))
        pin.framesForwardKinematics(r.model.model, r.model.data, q)
        return np.asarray(r.model.data.oMf[chain.tip_frame].translation.copy())

    # ------------------------------------------------------------------ moving
    def move(self, robot: str, chain: Chain, goal: Vector, target_world: pin.SE3, timeout: float | None,
             answer: dict[str, object], error_field: str | None = "final_error") -> Deferred:
        """Start moving ``chain`` to ``goal``; the Deferred answers ``answer`` plus ``error_field`` (the tip's
        position error measured in the simulation [m]) once the arm has settled, or fails after ``timeout`` [s] of
        simulated time with the error reached (``None``: the trajectory's duration plus 5 s)."""
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
        target_root = r.base_pose().actInv(target_world)
        self._drive(r, motion)

        def final_error() -> float:
            target = r.base_pose().act(target_root).translation
            return float(np.linalg.norm(r.tip_position(chain) - target))

        def poll() -> dict[str, object] | None:
            if motion.superseded:
                raise MoveError(f"arm '{chain.name}' {motion.reason} (tip error then {final_error():.4g} m)")
            if motion.settled:
                return {**answer, error_field: final_error()} if error_field else dict(answer)
            if self.sim.time >= motion.deadline:
                motion.settled = True  # stop adjusting; the servos hold the last targets
                angles_now, _ = r.chain_state(chain)
                raise MoveError(f"arm '{chain.name}' did not settle within {timeout:g} s: tip error "
                                f"{final_error():.4g} m, largest joint error "
                                f"{float(np.max(np.abs(goal - angles_now))):.3g} rad (blocked or overloaded?)")
            return None

        return Deferred(poll, timeout + 1.0, now)

    def _drive(self, r: RobotIk, motion: ArmMotion) -> None:
        angles, speeds = r.chain_state(motion.chain)
        gravity = chain_gravity(r.model, motion.chain, r.configuration(), r.gravity_in_root())
        targets, torques = motion.update(self.sim.time, self.sim.dt, angles, speeds, gravity)
        handle = self.sim.robot(r.name)
        dynamic = self.sim.modes(r.name)["dynamics"]
        for joint, target, torque in zip(motion.chain.joints, targets, torques, strict=True):
            handle.set_joint_target(joint, float(target))
            if torque != 0.0 and dynamic:
                handle.add_joint_torque(joint, float(torque))
        motion.holding = bool(np.any(torques != 0.0))

    def _on_step(self, sim: Simulation) -> None:
        for motion in self.motions.values():
            if not motion.superseded and (not motion.settled or motion.holding):
                self._drive(self.robots[motion.robot], motion)

    def reset(self) -> None:
        """The simulation was reset: moves in progress are answered with an error and forgotten."""
        for motion in self.motions.values():
            if not motion.settled:
                motion.superseded, motion.reason = True, "was stopped by a simulation reset"
        self.motions.clear()

    def summary(self) -> dict[str, object]:
        """Number of solves and the arms of each robot."""
        return {"solves": self.solves, "arms": {n: [c.name for c in r.chains] for n, r in self.robots.items()}}


def finite(value: float, field: str) -> float:
    """``value`` if finite, else :class:`InvalidTargetError` naming ``field``."""
    if not math.isfinite(value):
        raise InvalidTargetError(f"{field} is {value}; valid: a finite number")
    return value
