"""The IK view of one robot in a simulation: its Pinocchio model, its arms, and its current state."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .chain import Chain, build_chain, infer_chains
from .exceptions import UnknownChainError, UnknownFrameError
from .model import RobotModel, Vector

if TYPE_CHECKING:
    from sigcore.sim import Simulation


def se3(position: Vector, wxyz: Vector) -> pin.SE3:
    """An SE3 from a position [m] and a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(v) for v in wxyz)
    return pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.asarray(position, dtype=float))


class RobotIk:
    """A robot of the simulation with its kinematic model and arms.

    Args:
        sim: The simulation.
        name: Robot name.

    Raises:
        ValueError: an ``<arm>`` is not a chain of the URDF, or the robot has neither ``<arm>`` nor ``<gripper>``.
    """

    def __init__(self, sim: Simulation, name: str) -> None:
        self.sim, self.name = sim, name
        spec = sim.entities.robot_model(name)
        self.model = RobotModel(sim.world.urdf(name))
        sides = {g.part: g.side for g in spec.grippers}
        if spec.arms:
            self.chains = [build_chain(self.model, a.name, a.base, a.tip, sides.get(a.tip)) for a in spec.arms]
        elif spec.grippers:
            self.chains = infer_chains(self.model, [(g.part, g.side) for g in spec.grippers])
        else:
            raise ValueError(f"robot '{name}' has no <arm name=... base=... tip=...> and no <gripper part=...> "
                             "to infer an arm from; add one to the robot in the world file")
        self.kp = spec.gains.kp
        self.kv = spec.gains.kv
        self.gravity_world = np.asarray(sim.world.gravity, dtype=float)

    # ------------------------------------------------------------------ names
    def chain(self, name: str) -> Chain:
        """The arm called ``name``, or whose gripper side is ``name`` (``left``/``right``); the only arm if
        ``name`` is empty and there is one.

        Raises:
            UnknownChainError: listing the arm names and sides.
        """
        for c in self.chains:
            if name in (c.name, c.side) or (not name and len(self.chains) == 1):
                return c
        valid = [c.name for c in self.chains] + [c.side for c in self.chains if c.side]
        raise UnknownChainError(self.name, name, valid)

    # ------------------------------------------------------------------ state
    def base_pose(self) -> pin.SE3:
        """World pose of the URDF root link, from the backend now."""
        pos, quat = self.sim.backend.get_pose(self.name, self.model.root)
        return se3(pos, quat)

    def frame_pose(self, frame: str) -> pin.SE3:
        """World pose of ``world`` (identity) or of a link of the robot.

        Raises:
            UnknownFrameError: listing ``world`` and the links.
        """
        if frame in ("", "world"):
            return pin.SE3.Identity()
        if frame not in self.model.links:
            raise UnknownFrameError(frame, ("world", *self.model.links))
        pos, quat = self.sim.backend.get_pose(self.name, frame)
        return se3(pos, quat)

    def configuration(self) -> Vector:
        """Current full configuration from the backend's joint angles."""
        backend = self.sim.backend
        return self.model.configuration({j: backend.get_joint_angle(self.name, j)
                                         for j in backend.joints(self.name)})

    def chain_state(self, chain: Chain) -> tuple[Vector, Vector]:
        """Measured angles and speeds of the chain's joints, shape ``(n,)`` each."""
        backend = self.sim.backend
        angles = np.array([backend.get_joint_angle(self.name, j) for j in chain.joints])
        speeds = np.array([backend.get_joint_velocity(self.name, j) for j in chain.joints])
        return angles, speeds

    def gravity_in_root(self) -> Vector:
        """The world's gravity in the root link frame [m/s^2]."""
        return np.asarray(self.base_pose().rotation.T @ self.gravity_world)

    def tip_position(self, chain: Chain) -> Vector:
        """World position of the chain's tip link measured in the simulation [m]."""
        return self.sim.backend.get_pose(self.name, chain.tip)[0]
