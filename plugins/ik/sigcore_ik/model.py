"""The Pinocchio model of one robot, built from its own URDF, and the map between its joints and the backend's."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from sigcore.world.urdf import UrdfDocument

Vector = npt.NDArray[np.float64]


class RobotModel:
    """Kinematics of a URDF robot with a fixed base at the URDF root link (the robot's world pose is applied
    separately, so a mobile robot uses its current base pose).

    Args:
        urdf: The parsed URDF (``World.urdf``: the model is built from its text, the file is not read again), or
            a URDF file to read; only the kinematic tree, limits and inertias are used (no meshes).

    Attributes:
        model: The Pinocchio model; its universe frame is the URDF root link frame.
        data: Its working data.
        root: Name of the URDF root link.
    """

    def __init__(self, urdf: UrdfDocument | Path) -> None:
        document = UrdfDocument.read(urdf) if isinstance(urdf, Path) else urdf
        self.model: pin.Model = pin.buildModelFromXML(document.text)
        self.data: pin.Data = self.model.createData()
        self.root: str = self.model.frames[1].name if len(self.model.frames) > 1 else "universe"
        self._joint_ids = {self.model.names[i]: i for i in range(1, self.model.njoints)}
        self.links: tuple[str, ...] = tuple(f.name for f in self.model.frames if f.type == pin.FrameType.BODY)

    # ------------------------------------------------------------------ names
    def joint_id(self, name: str) -> int:
        """Pinocchio joint index of the URDF joint ``name`` (``KeyError`` if it is not movable)."""
        return self._joint_ids[name]

    @property
    def joint_names(self) -> list[str]:
        """Movable joints in model order."""
        return list(self._joint_ids)

    def frame_id(self, link: str) -> int:
        """Frame index of URDF link ``link`` (``KeyError`` listing the links otherwise)."""
        if link not in self.links:
            raise KeyError(f"no link '{link}'; links: {', '.join(self.links)}")
        return int(self.model.getFrameId(link, pin.FrameType.BODY))

    def parent_link(self, link: str) -> tuple[str, str | None]:
        """``(parent link, movable joint name or None)`` of ``link``; ``("", None)`` for the root."""
        frame = self.model.frames[self.frame_id(link)]
        if frame.parentFrame == 0:
            return "", None
        parent = self.model.frames[frame.parentFrame]  # the joint frame (movable or fixed) above the link
        if parent.type == pin.FrameType.JOINT:
            grand = self.model.frames[parent.parentFrame]
            return grand.name, parent.name
        if parent.type == pin.FrameType.FIXED_JOINT:
            return self.model.frames[parent.parentFrame].name, None
        return "", None

    # ------------------------------------------------------------------ configurations
    def configuration(self, angles: Mapping[str, float]) -> Vector:
        """Full configuration ``q`` (shape ``(nq,)``) from joint angles by name; missing joints at 0. A
        continuous joint is stored as (cos, sin)."""
        q = pin.neutral(self.model)
        for name, angle in angles.items():
            i = self._joint_ids.get(name)
            if i is None:
                continue
            joint = self.model.joints[i]
            if joint.nq == 2:
                q[joint.idx_q:joint.idx_q + 2] = (np.cos(angle), np.sin(angle))
            else:
                q[joint.idx_q] = angle
        return q

    def angle(self, q: Vector, joint: str) -> float:
        """Angle [rad] or position [m] of ``joint`` in configuration ``q``."""
        j = self.model.joints[self._joint_ids[joint]]
        if j.nq == 2:
            return float(np.arctan2(q[j.idx_q + 1], q[j.idx_q]))
        return float(q[j.idx_q])

    def gravity(self, q: Vector, gravity_in_root: Vector) -> Vector:
        """Joint torques [N m] that hold configuration ``q`` against gravity (shape ``(nv,)``).

        Args:
            q: Full configuration.
            gravity_in_root: Gravity vector in the root link frame [m/s^2] (the base may be tilted).
        """
        self.model.gravity.linear = gravity_in_root
        return pin.computeGeneralizedGravity(self.model, self.data, q).copy()
