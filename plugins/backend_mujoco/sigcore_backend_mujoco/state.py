"""Poses, velocities, centres of mass and wrenches of :class:`~.backend.MujocoBackend`'s entities (a mixin)."""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from sigcore.backend import Array
from sigcore.geometry import normalized as unit
from sigcore.geometry import quat_to_matrix

from .base import MujocoBase


class MujocoState(MujocoBase):
    """Reading and writing where the entities are and how they move."""

    def get_pose(self, entity: str, part: str | None = None) -> tuple[Array, Array]:
        """World position [m] and orientation (w, x, y, z) of the part's body frame (the URDF link frame)."""
        body = self._entity(entity).body(part)
        self._sync()
        return self.data.xpos[body].copy(), self.data.xquat[body].copy()

    def get_poses(self, parts: Sequence[tuple[str, str | None]]) -> Array:
        """Every part's pose from ``xpos``/``xquat`` in one indexing (about a tenth of a call per part); the body
        indices of a list of parts asked for again (a viewer's, a recorder's every frame) are looked up once."""
        key = parts if isinstance(parts, tuple) else tuple(parts)
        bodies = self._pose_rows.get(key)
        if bodies is None:
            bodies = np.array([self._entity(entity).body(part) for entity, part in key], dtype=np.intp)
            if len(self._pose_rows) >= 32:
                self._pose_rows.clear()
            self._pose_rows[key] = bodies
        self._sync()
        out = np.empty((len(bodies), 7))
        out[:, :3] = self.data.xpos[bodies]
        out[:, 3:] = self.data.xquat[bodies]
        return out

    def set_pose(self, entity: str, position: Array | None = None, quaternion: Array | None = None) -> None:
        """Teleport the main part: its free joint's ``qpos``, or ``body_pos``/``body_quat`` if welded."""
        e = self._entity(entity)
        if e.welded:
            if position is not None:
                self.model.body_pos[e.root] = position
            if quaternion is not None:
                self.model.body_quat[e.root] = unit(quaternion)
        else:
            a = e.free_qpos
            if position is not None:
                self.data.qpos[a:a + 3] = position
            if quaternion is not None:
                self.data.qpos[a + 3:a + 7] = unit(quaternion)
            self._update_hold(e)
        self._tick += 1

    def get_velocity(self, entity: str, part: str | None = None) -> tuple[Array, Array]:
        """Linear [m/s] and angular [rad/s] velocity of the part's frame origin, world frame."""
        body = self._entity(entity).body(part)
        self._sync()
        res = np.zeros(6)
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_XBODY, body, res, 0)
        return res[3:6].copy(), res[0:3].copy()

    def set_velocity(self, entity: str, linear: Array | None = None, angular: Array | None = None) -> None:
        """Set the free joint's velocity (its angular part is body-local in MuJoCo); no effect if welded."""
        e = self._entity(entity)
        if e.welded:
            return
        d, v = self.data, e.free_dof
        if linear is not None:
            d.qvel[v:v + 3] = linear
        if angular is not None:
            rot = quat_to_matrix(unit(d.qpos[e.free_qpos + 3:e.free_qpos + 7]))
            d.qvel[v + 3:v + 6] = rot.T @ np.asarray(angular, dtype=np.float64)
        self._tick += 1

    def get_com(self, entity: str, part: str | None = None) -> Array:
        """Centre of mass [m] of a robot link, or of a whole object or human (all its bodies)."""
        e = self._entity(entity)
        body = e.body(part)
        self._sync()
        if e.kind != "robot":
            return self.data.subtree_com[e.root].copy()
        return self.data.xipos[body].copy()

    def apply_wrench(self, entity: str, part: str | None, force: Array, torque: Array) -> None:
        """Add to ``xfrc_applied`` of the part's body (at its centre of mass) for the next step."""
        body = self._entity(entity).body(part)
        self.data.xfrc_applied[body, 0:3] += force
        self.data.xfrc_applied[body, 3:6] += torque
        self._applied = self._post = True
