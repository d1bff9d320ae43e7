"""Masses and the gravity, dynamics and collision modes of :class:`~.backend.MujocoBackend`'s entities (a mixin)."""

from __future__ import annotations

import numpy as np

from sigcore.errors import BackendRefusal

from .base import MujocoBase
from .layout import EntityIndex
from .recompile import scale_mass


class MujocoModes(MujocoBase):
    """Mass scaling and the per-entity modes: gravity compensation, holding (dynamics off), collision bits."""

    def get_mass(self, entity: str) -> float:
        """Sum of the masses [kg] of the entity's bodies."""
        return float(self.model.body_mass[self._entity(entity).bodies].sum())

    def set_mass(self, entity: str, mass: float) -> None:
        """Scale every body's mass and inertia so that they total ``mass`` [kg]; then ``mj_setConst``."""
        e = self._entity(entity)
        if float(self.model.body_mass[e.bodies].sum()) <= 0.0:
            raise BackendRefusal(f"{e.kind} '{e.name}' has no mass to scale (its URDF has no <inertial>)")
        self._scale_mass(e, mass)

    def _scale_mass(self, e: EntityIndex, mass: float) -> None:
        self._scratch = scale_mass(self.model, e, mass, self._scratch)

    def set_gravity_mode(self, entity: str, enabled: bool) -> None:
        """Gravity off: ``body_gravcomp = 1`` on every body of the entity (and ``flg_gravcomp`` on)."""
        e = self._entity(entity)
        m = self.model
        m.body_gravcomp[e.bodies] = 0.0 if enabled else 1.0
        m.flg_gravcomp = bool(np.any(m.body_gravcomp))

    def set_dynamics_mode(self, entity: str, enabled: bool) -> None:
        """Dynamics off holds every joint of the entity (free joint included) where it is now; a person's dynamics on
        locks its joints at their angles (joint equalities: a mannequin whose root is free).

        Raises:
            BackendRefusal: enabling dynamics of a static object (it has no joints).
        """
        e = self._entity(entity)
        if e.qpos.size == 0:
            if enabled:
                raise BackendRefusal(f"{e.kind} '{e.name}' is static (static=\"true\" in the world file) and "
                                   "cannot become dynamic; move it with set_pose")
            return
        if enabled:
            self._held.discard(e.name)
        else:
            self._held.add(e.name)
            self._hold[e.qpos] = self.data.qpos[e.qpos]
            self.data.qvel[e.dofs] = 0.0
            self._tick += 1
        self._lock_joints(e, enabled)
        self._bits.hold_person(self.model, e, not enabled)
        self._rebuild_held()

    def set_collision_mode(self, entity: str, enabled: bool) -> None:
        """Collision off zeroes ``contype``/``conaffinity`` of the entity's geoms; on restores them."""
        e = self._entity(entity)
        if enabled:
            self._bits.disabled.discard(e.name)
        else:
            self._bits.disabled.add(e.name)
        self._bits.apply(self.model, e)
