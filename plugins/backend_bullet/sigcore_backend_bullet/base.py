"""What every part of :class:`~.backend.BulletBackend` shares: its bookkeeping attributes, and the helpers that
several parts call (entity lookup, link frames, servo targets and wake-up, holding an entity in place, a person's
posture, collision filters). The parts are mixins of :class:`BulletBase`: :mod:`.state`, :mod:`.modes`,
:mod:`.joints`, and :mod:`.backend` itself (life cycle, stepping, run-time changes, grasps, contacts and rays).

A person (``<human>``) is held (static, or dynamics off) or dynamic, and its body is built for that:

* **held**: its joints are ``continuous`` (no limit constraint), its base has mass 0 (PyBullet's fixed base: the
  feet stay where they are, at no cost), and every other link weighs :data:`HELD_MASS_SCALE` times its mass; after
  every step one ``resetJointStatesMultiDof`` puts the joints back at the posture (velocities 0). Nothing it meets
  moves it (a link 1000 times as heavy yields a thousandth of what it would, and is put back), and what it is moved
  into (``set_pose``, ``set_joint_angle``) is pushed out of its way. Its links collide as static ones (see
  :mod:`.layout`). Zero-mass links would cost nothing per step, but PyBullet's contacts with them push nothing.
* **dynamic**: a rigid mannequin, every joint ``fixed`` at its angle (PyBullet's constraint solver cannot hold
  revolute joints of a free-floating person still: limits set to the angle sag 0.01 rad and jitter, and joints put
  back after each step feed energy in until the body flies off). Setting one of its angles, or switching its
  dynamics, builds its body again (``loadURDF``, about 6 ms; the base keeps its pose and velocity).
"""

from __future__ import annotations

from collections.abc import Sequence

import pybullet as pb

from sigcore.backend import Backend, find_entity
from sigcore.world.models import World

from .builder import rebuild_human
from .frames import compose, invert
from .layout import BASE, EntityIndex, JointIndex
from .pairs import PairFilters
from .servo import ServoBank

HELD_MASS_SCALE = 1000.0
"""A held person's links (all but its base, which has mass 0) weigh this many times their mass (see above)."""


class BulletBase(Backend):
    """The bookkeeping of the PyBullet backend and the helpers its parts share (see the module docstring)."""

    client: int
    _world: World
    _entities: dict[str, EntityIndex]
    _servos: dict[str, ServoBank]
    _mass: dict[str, list[float]]
    _nograv: set[str]
    _held: dict[str, tuple[list[float], list[float], list[float]]]
    _frozen: set[str]
    _posture: dict[str, list[float]]
    """The joint angles [rad] of every person, in URDF order: what its joints are held at."""
    _posed: set[str]
    """The held persons, whose joints are put back at their posture after every step."""
    _entities_changed: bool
    _collision_off: set[str]
    _pairs: PairFilters
    _tick: int
    _filters_changed: bool

    def _client(self) -> int:
        self.require_world()
        return self.client

    def _entity(self, name: str) -> EntityIndex:
        self.require_world()
        return find_entity(self._entities, name)

    def _frame(self, e: EntityIndex, link: int) -> tuple[Sequence[float], Sequence[float]]:
        """World pose of a link's URDF frame, ``(x, y, z, w)``."""
        c = self.client
        if link == BASE:
            pos, orn = pb.getBasePositionAndOrientation(e.body, physicsClientId=c)
            inv_pos, inv_orn = invert(e.local_pos, e.local_orn)
            return compose(pos, orn, inv_pos, inv_orn)
        state = pb.getLinkState(e.body, link, computeForwardKinematics=1, physicsClientId=c)
        return state[4], state[5]

    def _position_servo(self, e: EntityIndex, j: JointIndex, angle: float) -> None:
        self._servos[e.name].hold(j.index, angle)  # the motor is set before each step (see servo.py)

    def _wake(self) -> None:
        """Something may push an arm: every servo bank updates its motors again (see servo.py)."""
        for bank in self._servos.values():
            bank.wake()

    def _hold(self, e: EntityIndex, initial: bool = False) -> None:
        """Dynamics off: a single-link body becomes static (zero mass: nothing to do per step, as a static object
        costs); a person is held as the module docstring says; anything else is put back where it is now after
        every step (see ``_restore_held``)."""
        c = self.client
        if e.kind == "human":
            self._hold_human(e, initial)
            return
        if len(e.links) == 1 and not e.welded:
            if e.name not in self._frozen:
                pb.resetBaseVelocity(e.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
                pb.changeDynamics(e.body, BASE, mass=0.0, physicsClientId=c)
                self._filter(e, e.name not in self._collision_off)  # PyBullet gave it the default static filter
                self._frozen.add(e.name)
                self._filters_changed |= not initial  # it was re-inserted in the broadphase: reset rebuilds
            return
        pos, orn = pb.getBasePositionAndOrientation(e.body, physicsClientId=c)
        indices = e.joint_indices
        angles = [float(s[0]) for s in pb.getJointStates(e.body, indices, physicsClientId=c)] if indices else []
        self._held[e.name] = (list(pos), list(orn), angles)
        if not e.welded:
            pb.resetBaseVelocity(e.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
        self._reset_joints(e, angles)

    def _reset_joints(self, e: EntityIndex, angles: Sequence[float]) -> None:
        """Every movable joint of ``e`` at its angle in ``angles`` (URDF order), at rest (one PyBullet call)."""
        if angles:
            pb.resetJointStatesMultiDof(e.body, e.joint_indices, [[q] for q in angles], [[0.0]] * len(angles),
                                        physicsClientId=self.client)

    def _hold_human(self, e: EntityIndex, initial: bool) -> None:
        """Hold a person: a mannequin gets a body with kinematic joints; its base gets mass 0, its other links
        :data:`HELD_MASS_SCALE` times theirs, its collision filters those of static links (module docstring)."""
        if e.rigid:
            e = self._rebuild_human(e, rigid=False)
        self._posed.add(e.name)
        if e.name in self._frozen:
            return
        c = self.client
        pb.resetBaseVelocity(e.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
        pb.changeDynamics(e.body, BASE, mass=0.0, physicsClientId=c)
        for mass, inertia, link in zip(e.masses0[1:], e.inertia0[1:], e.links[1:], strict=True):
            pb.changeDynamics(e.body, link, mass=mass * HELD_MASS_SCALE,
                              localInertiaDiagonal=[x * HELD_MASS_SCALE for x in inertia], physicsClientId=c)
        self._reset_joints(e, self._posture[e.name])
        e.still = True
        self._filter(e, e.name not in self._collision_off)
        self._frozen.add(e.name)
        self._filters_changed |= not initial  # it was re-inserted in the broadphase: reset rebuilds

    def _rebuild_human(self, e: EntityIndex, rigid: bool) -> EntityIndex:
        """Give the person ``e`` a new body, rigid (a dynamic mannequin) or with kinematic joints (to be held), at
        its posture, with its base's pose and velocity, its masses and collision mode (see :mod:`.builder`).
        Its part ids are renumbered; the next reset rebuilds the world (its saved state holds the old body)."""
        c = self.client
        new = rebuild_human(c, self._world, e, self._posture[e.name], rigid)
        for i, (mass, mass0) in enumerate(zip(self._mass[e.name], new.masses0, strict=True)):
            if mass != mass0 and mass0 > 0.0:
                pb.changeDynamics(new.body, new.links[i], mass=mass,
                                  localInertiaDiagonal=[x * mass / mass0 for x in new.inertia0[i]],
                                  physicsClientId=c)
        self._entities[e.name] = new
        self._frozen.discard(e.name)
        self._posed.discard(e.name)
        self._filter(new, e.name not in self._collision_off)
        self._index()
        self._entities_changed = True
        return new

    def _index(self) -> None:
        """Part ids, the contact map and the possible grasps, from ``_entities`` (see :mod:`.backend`)."""
        raise NotImplementedError

    def _filter(self, e: EntityIndex, enabled: bool) -> None:
        for link in e.links:
            pb.setCollisionFilterGroupMask(e.body, link, *e.filter_bits(link, enabled), physicsClientId=self.client)
        self._sync_pairs()

    def _bits(self, e: EntityIndex, link: int) -> tuple[int, int]:
        """Collision ``(group, mask)`` of a link as the entity's collision mode says now."""
        return e.filter_bits(link, e.name not in self._collision_off)

    def _sync_pairs(self) -> None:
        """Pair filter entries back to the groups and masks (see :mod:`.pairs`)."""
        self._pairs.sync(self.client, {e.body: e for e in self._entities.values()}, self._bits)
