"""Masses and the gravity, dynamics and collision modes of :class:`~.backend.BulletBackend`'s entities (a mixin)."""

from __future__ import annotations

import pybullet as pb

from sigcore.errors import BackendRefusal

from .base import BulletBase
from .layout import BASE


class BulletModes(BulletBase):
    """Mass scaling and the per-entity modes: gravity compensation, holding (dynamics off), collision filters."""

    def get_mass(self, entity: str) -> float:
        """Sum of the masses [kg] of the entity's links."""
        return float(sum(self._mass[self._entity(entity).name]))

    def set_mass(self, entity: str, mass: float) -> None:
        """Scale every link's mass and inertia so that they total ``mass`` [kg] (``changeDynamics``)."""
        self._wake()
        e = self._entity(entity)
        masses = self._mass[entity]
        total = sum(masses)
        if total <= 0.0:
            raise BackendRefusal(f"{e.kind} '{e.name}' has no mass to scale (its URDF has no <inertial>)")
        factor = mass / total
        for i, link in enumerate(e.links):
            masses[i] *= factor
            if not e.static and masses[i] > 0.0 and e.name not in self._frozen:  # frozen: mass back when freed
                inertia = [x * masses[i] / e.masses0[i] for x in e.inertia0[i]]
                pb.changeDynamics(e.body, link, mass=masses[i], localInertiaDiagonal=inertia,
                                  physicsClientId=self.client)

    def set_gravity_mode(self, entity: str, enabled: bool) -> None:
        """Gravity off: a force ``-m g`` at every link's centre of mass before each step."""
        self._wake()
        e = self._entity(entity)
        if enabled:
            self._nograv.discard(e.name)
        else:
            self._nograv.add(e.name)

    def set_dynamics_mode(self, entity: str, enabled: bool) -> None:
        """Dynamics off holds the base and every joint where they are now. A person with dynamics on is a rigid
        mannequin at its posture (a new body; see :mod:`.base`).

        Raises:
            BackendRefusal: enabling dynamics of a static object (PyBullet holds it with mass 0).
        """
        self._wake()
        e = self._entity(entity)
        if e.kind == "human":
            if enabled and e.name in self._posed:
                self._rebuild_human(e, rigid=True)
            elif not enabled:
                self._hold(e)
            self._tick += 1
            return
        if e.static:
            if enabled:
                raise BackendRefusal(f"{e.kind} '{e.name}' is static (static=\"true\" in the world file) and "
                                   "cannot become dynamic; move it with set_pose")
            return
        if enabled:
            self._held.pop(e.name, None)
            if e.name in self._frozen:
                self._frozen.discard(e.name)
                mass, mass0 = self._mass[e.name][0], e.masses0[0]
                inertia = [x * mass / mass0 for x in e.inertia0[0]] if mass0 > 0.0 else list(e.inertia0[0])
                pb.changeDynamics(e.body, BASE, mass=mass, localInertiaDiagonal=inertia, physicsClientId=self.client)
                self._filter(e, e.name not in self._collision_off)
                self._filters_changed = True
        else:
            self._hold(e)
            self._tick += 1

    def set_collision_mode(self, entity: str, enabled: bool) -> None:
        """Collision off puts every link in a filter group that collides with nothing (rays still see it; see the
        table in :mod:`.layout`)."""
        self._wake()
        e = self._entity(entity)
        if enabled == (e.name not in self._collision_off):
            return
        if enabled:
            self._collision_off.discard(e.name)
        else:
            self._collision_off.add(e.name)
        self._filters_changed = True
        self._filter(e, enabled)
