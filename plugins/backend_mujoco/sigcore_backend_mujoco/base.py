"""What every part of :class:`~.backend.MujocoBackend` shares: its model and data, its bookkeeping attributes, and
the helpers that several parts call (entity lookup, fresh kinematics on read, held entities). The parts are mixins
of :class:`MujocoBase`: :mod:`.state`, :mod:`.modes`, :mod:`.joints`, and :mod:`.backend` itself (life cycle,
stepping, run-time changes, grasps, contacts and rays).
"""

from __future__ import annotations

import mujoco
import numpy as np

from sigcore.backend import Backend, find_entity

from .collision import CollisionBits
from .layout import EntityIndex

_NO_INTS = np.zeros(0, dtype=np.int64)


class MujocoBase(Backend):
    """The bookkeeping of the MuJoCo backend and the helpers its parts share (see the module docstring)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    _entities: dict[str, EntityIndex]
    _pose_rows: dict[tuple[tuple[str, str | None], ...], np.ndarray]
    """:meth:`get_poses`' body indices per list of parts asked for (a viewer's, a recorder's), for this model."""
    _scratch: mujoco.MjData | None
    _bits: CollisionBits
    _tick: int
    _synced: int
    _applied: bool
    _post: bool
    _held: set[str]
    _hold: np.ndarray
    _held_qpos: np.ndarray
    _held_dofs: np.ndarray
    _held_values: np.ndarray
    _hold_views: tuple[np.ndarray | None, np.ndarray | None]
    """The held qpos and dofs as views of ``data.qpos`` and ``data.qvel`` (None: not one contiguous run)."""

    def _entity(self, name: str) -> EntityIndex:
        self.require_world()
        return find_entity(self._entities, name)

    def _sync(self) -> None:
        """Bring poses, centres of mass and velocities in ``data`` up to date with ``qpos``/``qvel``."""
        if self._synced != self._tick:
            m, d = self.model, self.data
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
            mujoco.mj_comVel(m, d)
            self._synced = self._tick

    def _rebuild_held(self) -> None:
        held = [self._entities[n] for n in sorted(self._held)]
        self._held_qpos = np.concatenate([e.qpos for e in held]) if held else _NO_INTS
        self._held_dofs = np.concatenate([e.dofs for e in held]) if held else _NO_INTS
        self._held_values = self._hold[self._held_qpos]
        self._hold_views = _views(self.data.qpos, self._held_qpos), _views(self.data.qvel, self._held_dofs)
        self._post = bool(self._held_qpos.size) or self._applied

    def _lock_joints(self, e: EntityIndex, active: bool) -> None:
        """Switch a person's joint locks (its dynamics on: a mannequin whose joints keep their angles)."""
        for j in e.joints.values():
            if j.lock >= 0:
                self.model.eq_data[j.lock, 0] = self.data.qpos[j.qpos]
                self.data.eq_active[j.lock] = 1 if active else 0

    def _update_hold(self, e: EntityIndex) -> None:
        if e.name in self._held:
            self._hold[e.qpos] = self.data.qpos[e.qpos]
            self.data.qvel[e.dofs] = 0.0
            self._held_values = self._hold[self._held_qpos]


def _views(array: np.ndarray, index: np.ndarray) -> np.ndarray | None:
    """``array[index]`` as a view when ``index`` is one contiguous run (a held entity's qpos or dofs; written in
    place after every step: a slice view costs a third of a fancy-indexed write), else None."""
    if not index.size or not np.array_equal(index, np.arange(index[0], index[0] + index.size)):
        return None
    return array[index[0]:index[0] + index.size]
