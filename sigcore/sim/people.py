"""What moves the people of a world (``sim.entities.people``): the one owner of each person's motion source.

A person (``<human>``) is held kinematically by the backend (:mod:`sigcore.world.body`); something must move it.
Each person has at most one motion source at a time. This module has one: **walking by velocity**
(:meth:`People.walk`, ``/<person>/cmd_vel``), a procedural gait (:mod:`sigcore.sim.gait`) that puts the feet frame
and every joint where the gait has them after each step, in simulated time. Nothing is done for a person that
stands (no step subscriber is due then, so the core's batched steps stay batched).

A walk's command goes through ``sim.inputs.person_velocity`` when it comes from outside (a transport, a viewer), so
that a recording replays it (:mod:`sigcore.sim.inputs`).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from ..agent.exceptions import ApiError
from ..geometry import quat_from_rpy, quat_yaw
from ..text import quote
from ..world.body import Body, human_body
from ..world.models import Entity, Human
from .gait import Gait

if TYPE_CHECKING:
    from .events import Subscription
    from .simulation import Simulation


class People:
    """The people of the running world and their motion (see the module docstring).

    Args:
        sim: The simulation (its backend built).
        entities: The world's entities (the people among them are kept).
    """

    def __repr__(self) -> str:
        return "<the people's motion>"

    def __init__(self, sim: Simulation, entities: Iterable[Entity]) -> None:
        self._sim = sim
        self._bodies: dict[str, Body] = {}
        self._gaits: dict[str, Gait] = {}
        self.add(entities)
        self._stepping: Subscription | None = None  # subscribed when someone first walks: a world pays nothing before

    @property
    def names(self) -> tuple[str, ...]:
        """The people, in world order."""
        return tuple(self._bodies)

    def body(self, person: str) -> Body:
        """The body of ``person``; ``ApiError`` listing the people otherwise."""
        body = self._bodies.get(person)
        if body is None:
            raise ApiError(f"no person {quote(person)}; people (<human>): {', '.join(self._bodies) or 'none'}")
        return body

    def walk(self, person: str, linear: float, angular: float) -> None:
        """Walk ``person`` at ``linear`` [m/s] forward (negative: backward) turning at ``angular`` [rad/s], from the
        next step on, until told otherwise (0, 0: it finishes its step and stands).

        Raises:
            ApiError: no such person, or a value out of range or not finite (the message names the valid range);
                nothing changes then.
        """
        body = self.body(person)
        gait = self._gaits.get(person)
        if gait is None:
            pos, quat = self._sim.backend.get_pose(person)
            gait = Gait(body, float(pos[0]), float(pos[1]), float(pos[2]), quat_yaw(quat))
        try:
            gait.command(float(linear), float(angular))
        except (TypeError, ValueError) as e:
            raise ApiError(f"walking {quote(person)}: {e}") from None
        self._gaits[person] = gait
        if self._stepping is None:
            self._stepping = self._sim.events.subscribe("step", self._on_step, owner=self)
        self._stepping.set_every(1)

    def velocity(self, person: str) -> tuple[float, float]:
        """The commanded ``(linear [m/s], angular [rad/s])`` of ``person``; (0, 0) when it stands."""
        self.body(person)
        gait = self._gaits.get(person)
        return (gait.linear, gait.angular) if gait is not None else (0.0, 0.0)

    def walking(self, person: str) -> bool:
        """Whether ``person`` walks, turns or finishes a step."""
        gait = self._gaits.get(person)
        return gait is not None and gait.moving

    def _on_step(self, _sim: Simulation) -> None:
        backend, dt = self._sim.backend, self._sim.dt
        for name, gait in list(self._gaits.items()):
            posture = gait.advance(dt)
            backend.set_pose(name, np.array([posture.x, posture.y, posture.z]), quat_from_rpy(0.0, 0.0, posture.yaw))
            backend.set_joint_angles(name, posture.angles)
            if not gait.moving:
                del self._gaits[name]  # it stands: the next walk starts from where it is then
        if not self._gaits and self._stepping is not None:
            self._stepping.set_every(0)

    # ------------------------------------------------------------------ entities come and go
    def add(self, entities: Iterable[Entity]) -> None:
        """People spawned (or the world's, at start)."""
        for e in entities:
            if isinstance(e, Human):
                self._bodies[e.name] = human_body(e.height, e.mass)

    def remove(self, names: Iterable[str]) -> None:
        """People deleted: their motion stops with them."""
        for name in names:
            self._bodies.pop(name, None)
            self._gaits.pop(name, None)

    def reset(self) -> None:
        """Everyone stands (a reset put them back at their world-file poses)."""
        self._gaits.clear()
        if self._stepping is not None:
            self._stepping.set_every(0)

    def close(self) -> None:
        """The world goes: the step subscription is detached."""
        self._sim.events.detach(self)

