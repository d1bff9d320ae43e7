"""Contacts between entities, and contact events: one event when a part of an agent starts touching another entity.

The backend reports pairs of touching part ids after each step; the tracker turns them into ``(entity, own part,
other entity)`` triples, both directions. The floor is the entity ``ground`` (``sigcore.backend.GROUND``, part
``main``): it is not an agent, so it receives no events, but agents receive ``ground`` as ``other``.

Events follow the meaning of SIGVerse's ``onCollision``: one per contact *episode* of a triple, not one per change of
the engine's contact set.

* A robot's wheels and casters on the floor are not collisions: the floor contacts of its rolling parts
  (:func:`rolling_parts`) start no episode. Their other contacts (a wheel against a wall) do.
* Flicker is debounced: an episode starts with the first step of contact and ends only after the triple has been
  apart for :data:`CONTACT_HOLD` of simulated time (counted in steps, so runs stay deterministic); a bouncing or
  grazing touch that resumes sooner is the same episode.

:meth:`ContactTracker.triples` stays raw (every current contact, wheels included): it answers "does this part
touch something now" (``_get_collision_state``) and lets features look at contacts themselves.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

from ..backend import GROUND, Backend
from ..world.models import Robot
from ..world.urdf import UrdfModel

Triple = tuple[str, str, str]
"""``(entity, own part, other entity)``."""

CONTACT_HOLD = 0.1
"""A contact episode ends when its triple has been apart for this long [s] (simulated time, rounded up to whole
steps, at least one step); a contact that resumes sooner is the same episode and starts no new event."""

CASTER_WORD = "caster"
"""Without ``<drive casters=...>``, a robot's casters are the URDF links whose name contains this word."""

_EMPTY: frozenset[Triple] = frozenset()


def rolling_parts(robot: Robot, urdf: UrdfModel) -> frozenset[str]:
    """Links of ``robot`` that roll or slide on the floor: its wheels and its casters.

    Args:
        robot: The robot's world model.
        urdf: The robot's URDF.

    Returns:
        The child links of the ``<drive>``'s wheel joints, plus the ``<drive>``'s ``casters`` if given, else every
        URDF link whose name contains ``"caster"`` (with or without a ``<drive>``).
    """
    drive = robot.drive
    casters: Iterable[str]
    if drive is not None and drive.casters is not None:
        casters = drive.casters
    else:
        casters = (link for link in urdf.links if CASTER_WORD in link)
    parts = set(casters)
    if drive is not None:
        parts |= {urdf.joint(drive.left).child, urdf.joint(drive.right).child}
    return frozenset(parts)


def hold_steps(hold: float, dt: float) -> int:
    """``hold`` [s] in whole steps of ``dt`` [s]: rounded up, at least one.

    Raises:
        ValueError: ``hold`` or ``dt`` is not a positive finite number.
    """
    if not (0 < dt < math.inf and 0 < hold < math.inf):
        raise ValueError(f"hold and dt must be positive finite numbers [s], got hold={hold!r}, dt={dt!r}")
    return max(1, math.ceil(hold / dt - 1e-9))


class ContactTracker:
    """Owns the contact state of a simulation: the current triples and the open contact episodes.

    Args:
        backend: The backend whose ``contacts()`` and ``part_of()`` are read.
        agents: Names of the agents (only agents receive events).
        rolling: Rolling parts (wheels, casters) of each robot, whose floor contacts start no episode.
        dt: The timestep [s].
        hold: How long a triple must be apart before its episode ends [s].

    Raises:
        ValueError: ``dt`` or ``hold`` is not a positive finite number.
    """

    def __init__(self, backend: Backend, agents: Iterable[str], rolling: Mapping[str, frozenset[str]],
                 dt: float, hold: float = CONTACT_HOLD) -> None:
        self._backend = backend
        self._agents = frozenset(agents)
        self._rolling = {robot: frozenset(parts) for robot, parts in rolling.items()}
        self._quiet = frozenset((robot, part, GROUND) for robot, parts in self._rolling.items() for part in parts)
        self.hold_steps = hold_steps(hold, dt)
        """``hold`` in whole steps."""
        self._step = -1  # step of the cached contacts
        self._pairs: frozenset[tuple[int, int]] = frozenset()
        self._triples = _EMPTY
        self._eventful = _EMPTY  # the triples that are episodes: an agent's, not a rolling part on the floor
        self._touching = _EMPTY  # ``_eventful`` when events() last looked
        self._apart: dict[Triple, int] = {}  # triple -> first step it was apart (its episode may go on)

    def rolling_parts(self, robot: str) -> frozenset[str]:
        """Wheels and casters of ``robot`` (empty for other entities): their floor contacts are no events."""
        return self._rolling.get(robot, frozenset())

    def triples(self, step: int) -> frozenset[Triple]:
        """Every contact after step ``step`` as ``(entity, own part, other entity)``, both directions, the floor
        and wheels included (read from the backend once per step)."""
        if self._step != step:
            self._refresh(step)
        return self._triples

    def _refresh(self, step: int) -> None:
        self._step = step
        pairs = self._backend.contacts()
        if pairs == self._pairs:
            return
        self._pairs = pairs
        part_of = self._backend.part_of
        agents, quiet = self._agents, self._quiet
        triples: set[Triple] = set()
        eventful: set[Triple] = set()
        for a, b in pairs:
            ea, pa = part_of(a)
            eb, pb = part_of(b)
            if ea == eb:
                continue
            for triple in ((ea, pa, eb), (eb, pb, ea)):
                triples.add(triple)
                if triple[0] in agents and triple not in quiet:
                    eventful.add(triple)
        self._triples = frozenset(triples)
        if eventful != self._eventful:  # keep the object when only quiet contacts changed: events() skips it
            self._eventful = frozenset(eventful)

    def events(self, step: int) -> list[Triple]:
        """The triples whose contact episode starts at step ``step``, sorted.

        Call it after every step while someone listens: episodes are followed only through these calls (a triple
        that separated and touched again between two calls is seen as touching all along).
        """
        if self._step != step:
            self._refresh(step)
        now, before = self._eventful, self._touching
        if now is before:
            return []
        self._touching = now
        apart = self._apart
        for triple in before - now:
            apart[triple] = step
        started = []
        for triple in now - before:
            since = apart.pop(triple, None)
            if since is None or step - since >= self.hold_steps:
                started.append(triple)
        started.sort()
        return started

    def set_agents(self, agents: Iterable[str], rolling: Mapping[str, frozenset[str]]) -> None:
        """The agents changed while running (spawned, deleted): the backend's part ids may be renumbered, so the
        contacts are read afresh at the next look; episodes of the agents that remain go on."""
        self._agents = frozenset(agents)
        self._rolling = {robot: frozenset(parts) for robot, parts in rolling.items()}
        self._quiet = frozenset((robot, part, GROUND) for robot, parts in self._rolling.items() for part in parts)
        self._step = -1
        self._pairs = frozenset()
        self._apart = {t: s for t, s in self._apart.items() if t[0] in self._agents and t[2] in self._agents | {GROUND}}

    def reset(self) -> None:
        """Forget every contact and close every episode (after the backend was reset): contacts present after the
        next step start new episodes."""
        self._step = -1
        self._pairs = frozenset()
        self._triples = self._eventful = self._touching = _EMPTY
        self._apart.clear()
