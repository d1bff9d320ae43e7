"""What every part of :class:`~.backend.BulletBackend` shares: its bookkeeping attributes, and the helpers that
several parts call (entity lookup, link frames, servo targets and wake-up, holding an entity in place, collision
filters). The parts are mixins of :class:`BulletBase`: :mod:`.state`, :mod:`.modes`, :mod:`.joints`, and
:mod:`.backend` itself (life cycle, stepping, run-time changes, grasps, contacts and rays).
"""

from __future__ import annotations

from collections.abc import Sequence

import pybullet as pb

from sigcore.backend import Backend, find_entity

from .frames import compose, invert
from .layout import BASE, EntityIndex, JointIndex
from .pairs import PairFilters
from .servo import ServoBank


class BulletBase(Backend):
    """The bookkeeping of the PyBullet backend and the helpers its parts share (see the module docstring)."""

    client: int
    _entities: dict[str, EntityIndex]
    _servos: dict[str, ServoBank]
    _mass: dict[str, list[float]]
    _nograv: set[str]
    _held: dict[str, tuple[list[float], list[float], list[float]]]
    _frozen: set[str]
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
        costs); anything else is put back where it is now after every step (see ``_restore_held``)."""
        c = self.client
        if len(e.links) == 1 and not e.welded:
            if e.name not in self._frozen:
                pb.resetBaseVelocity(e.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
                pb.changeDynamics(e.body, BASE, mass=0.0, physicsClientId=c)
                self._filter(e, e.name not in self._collision_off)  # PyBullet gave it the default static filter
                self._frozen.add(e.name)
                self._filters_changed |= not initial  # it was re-inserted in the broadphase: reset rebuilds
            return
        pos, orn = pb.getBasePositionAndOrientation(e.body, physicsClientId=c)
        angles = [float(pb.getJointState(e.body, j.index, physicsClientId=c)[0]) for j in e.joints.values()]
        self._held[e.name] = (list(pos), list(orn), angles)
        if not e.welded:
            pb.resetBaseVelocity(e.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
        for j, q in zip(e.joints.values(), angles, strict=True):
            pb.resetJointState(e.body, j.index, q, 0.0, physicsClientId=c)

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
