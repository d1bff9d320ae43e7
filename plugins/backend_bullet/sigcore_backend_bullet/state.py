"""Poses, velocities, centres of mass and wrenches of :class:`~.backend.BulletBackend`'s entities (a mixin)."""

from __future__ import annotations

import numpy as np
import pybullet as pb

from sigcore.backend import Array
from sigcore.geometry import cross

from . import grasp
from .base import BulletBase
from .frames import compose, to_wxyz, to_xyzw
from .layout import BASE

_ORIGIN = (0.0, 0.0, 0.0)


class BulletState(BulletBase):
    """Reading and writing where the entities are and how they move."""

    def get_pose(self, entity: str, part: str | None = None) -> tuple[Array, Array]:
        """World position [m] and orientation (w, x, y, z) of the part's URDF link frame."""
        e = self._entity(entity)
        pos, orn = self._frame(e, e.link(part))
        return np.array(pos, dtype=np.float64), to_wxyz(orn)

    def set_pose(self, entity: str, position: Array | None = None, quaternion: Array | None = None) -> None:
        """Teleport the base so that its URDF frame has this pose (``resetBasePositionAndOrientation``)."""
        self._wake()
        e = self._entity(entity)
        pos, orn = self._frame(e, BASE)
        new_pos = [float(x) for x in position] if position is not None else list(pos)
        new_orn = to_xyzw(quaternion) if quaternion is not None else list(orn)
        ipos, iorn = compose(new_pos, new_orn, e.local_pos, e.local_orn)
        pb.resetBasePositionAndOrientation(e.body, ipos, iorn, physicsClientId=self.client)
        if e.name in self._held:
            self._hold(e)
        self._tick += 1

    def get_velocity(self, entity: str, part: str | None = None) -> tuple[Array, Array]:
        """Linear [m/s] and angular [rad/s] velocity of the part's frame origin: ``v_com + w x (o - com)``."""
        e = self._entity(entity)
        link = e.link(part)
        c = self.client
        if link == BASE:
            lin, ang = pb.getBaseVelocity(e.body, physicsClientId=c)
            if e.local_pos == _ORIGIN:  # the frame origin is the centre of mass (a primitive object)
                return np.array(lin, dtype=np.float64), np.array(ang, dtype=np.float64)
            com = pb.getBasePositionAndOrientation(e.body, physicsClientId=c)[0]
            origin = self._frame(e, BASE)[0]
        else:
            s = pb.getLinkState(e.body, link, computeLinkVelocity=1, computeForwardKinematics=1,
                                physicsClientId=c)
            com, origin, lin, ang = s[0], s[4], s[6], s[7]
        w = np.array(ang, dtype=np.float64)
        v = np.array(lin, dtype=np.float64) + cross(ang, tuple(o - p for o, p in zip(origin, com, strict=True)))
        return v, w

    def set_velocity(self, entity: str, linear: Array | None = None, angular: Array | None = None) -> None:
        """Set the base's velocity (``resetBaseVelocity`` at its centre of mass); no effect if welded or a held
        person (its base is PyBullet's fixed base)."""
        self._wake()
        e = self._entity(entity)
        if e.welded or e.name in self._posed:
            return
        lin0, ang0 = self.get_velocity(entity)
        lin = np.asarray(linear, dtype=np.float64) if linear is not None else lin0
        ang = np.asarray(angular, dtype=np.float64) if angular is not None else ang0
        c = self.client
        com = pb.getBasePositionAndOrientation(e.body, physicsClientId=c)[0]
        origin = self._frame(e, BASE)[0]
        v_com = lin + cross(ang, np.subtract(com, origin))
        pb.resetBaseVelocity(e.body, v_com.tolist(), ang.tolist(), physicsClientId=c)
        self._tick += 1

    def get_com(self, entity: str, part: str | None = None) -> Array:
        """Centre of mass [m] of a robot link or a person's link, or of a whole object or person (all its links:
        the part ``None`` or ``main``)."""
        e = self._entity(entity)
        link = e.link(part)
        c = self.client
        if e.kind == "robot" or len(e.links) == 1 or link != BASE:
            return np.array(grasp.inertial_pose(c, e.body, link)[0], dtype=np.float64)
        masses = np.array(self._mass[entity])
        coms = np.array([grasp.inertial_pose(c, e.body, k)[0] for k in e.links])
        total = float(masses.sum())
        return (masses @ coms) / total if total > 0 else coms[0]

    def apply_wrench(self, entity: str, part: str | None, force: Array, torque: Array) -> None:
        """``applyExternalForce`` at the link's centre of mass and ``applyExternalTorque``, world frame (nothing on a
        held person)."""
        self._wake()
        e = self._entity(entity)
        link = e.link(part)
        c = self.client
        if e.name in self._posed:
            return
        if np.any(force):
            com = grasp.inertial_pose(c, e.body, link)[0]
            pb.applyExternalForce(e.body, link, [float(x) for x in force], com, pb.WORLD_FRAME, physicsClientId=c)
        if np.any(torque):
            pb.applyExternalTorque(e.body, link, [float(x) for x in torque], pb.WORLD_FRAME, physicsClientId=c)
