"""A person walking a path (``<path>`` in the world file, :meth:`sigcore.sim.people.People.follow` at run time):
what it is told to do at each step, and what is wrong with a path before it sets off.

:class:`PathWalker` turns a :class:`~sigcore.world.models.WalkPath` into the velocity commands of the person's gait
(:mod:`sigcore.sim.gait`), one per step, in simulated time:

* **Turn, then walk straight.** Setting off toward a waypoint, the person turns on the spot to face it at
  :data:`TURN_RATE`, then walks straight to it at the path's speed, the last step shortened so that the feet frame
  ends on the waypoint. The time to a waypoint is therefore its distance over the speed, plus the turn over
  :data:`TURN_RATE`, plus the waits, each rounded up to whole steps.
* **Waits at a waypoint**, in order: ``wait`` seconds after arriving, then until ``until_near`` (any entity) is within
  ``within`` m of the person on the floor plane, then until the person received ``until_message`` (a message to it
  from any agent since it set off toward the waypoint). The person stands meanwhile.
* **Then the next waypoint**; after the last, the first again with ``loop``, else the person stands there.

:func:`path_problems` says what makes a path impossible, before it is walked: a straight leg of it through a static
entity (a wall, a table: seen by rays at several heights between knee and head, through whatever can be pushed
aside, see :meth:`sigcore.backend.Backend.ray_hits`), a condition on a static entity that will never be near
enough, an ``until_near`` naming nothing in the world or the person itself.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..geometry import wrap_angle
from ..world.models import Entity, Human, Object, WalkPath, Waypoint
from .gait import MAX_TURN

TURN_RATE = 1.5
"""How fast a person turns on the spot toward its next waypoint [rad/s]."""
FACING = 0.05
"""The largest heading error [rad] at which a person walks on toward a waypoint (correcting as it goes); beyond it,
it turns on the spot first."""
_ARRIVED = 1e-6
"""How close to a waypoint the feet frame counts as on it [m] (the last step lands on it)."""
_RAY_HEIGHTS = (0.1, 0.25, 0.45, 0.65, 0.85, 1.05, 1.3, 1.55)
"""Heights of the rays along a leg of a path, as shares of 1.7 m (scaled with the person's height)."""

State = Literal["turning", "walking", "waiting", "done"]


@dataclass(frozen=True)
class Progress:
    """Where a person is on its path.

    Attributes:
        waypoint: The waypoint it walks toward or waits at (0-based).
        of: How many waypoints the path has.
        state: ``turning`` (on the spot, toward it), ``walking``, ``waiting`` (at it), ``done`` (at the last one).
        waiting_for: While waiting, what for (``"2.0 s"``, ``"robot_0 within 2 m"``, ``"message 'go'"``); else "".
        laps: How many times a looping path went round.
    """

    waypoint: int
    of: int
    state: State
    waiting_for: str = ""
    laps: int = 0


class PathWalker:
    """One person's walk along one path (see the module docstring).

    Args:
        path: The path.
        distance_to: The distance [m] on the floor plane from the person to an entity, or None when it is gone.
    """

    def __init__(self, path: WalkPath, distance_to: Callable[[str], float | None]) -> None:
        self.path = path
        self._distance_to = distance_to
        self.index = 0
        self.state: State = "turning"
        self.laps = 0
        self._arrived_at = self._now = 0.0
        self._heard: set[str] = set()

    @property
    def target(self) -> Waypoint:
        """The waypoint walked toward or waited at."""
        return self.path.waypoints[self.index]

    def hear(self, text: str) -> None:
        """A message to the person arrived."""
        self._heard.add(text)

    def progress(self) -> Progress:
        """Where the person is on the path."""
        return Progress(self.index, len(self.path.waypoints), self.state,
                        self._waiting_for(self._now) if self.state == "waiting" else "", self.laps)

    def command(self, x: float, y: float, yaw: float, now: float, dt: float) -> tuple[float, float]:
        """The velocity ``(linear [m/s], angular [rad/s])`` for the step from ``now`` [s] to ``now + dt``, the feet
        frame at ``(x, y, yaw)``."""
        self._now = now
        for _ in range(2):  # a wait that is over at once moves on to the next waypoint in the same step
            if self.state == "waiting":
                if self._waiting_for(now):
                    return 0.0, 0.0
                self._next()
            if self.state == "done":
                return 0.0, 0.0
            point = self.target
            dx, dy = point.x - x, point.y - y
            remaining = math.hypot(dx, dy)
            if remaining <= _ARRIVED:
                self.state, self._arrived_at = "waiting", now
                continue
            error = wrap_angle(math.atan2(dy, dx) - yaw)
            if self.state == "turning" and abs(error) > 1e-9 or abs(error) > FACING:
                self.state = "turning"
                turn = max(-TURN_RATE, min(TURN_RATE, error / dt))
                if abs(error - turn * dt) <= 1e-9:
                    self.state = "walking"
                return 0.0, turn
            self.state = "walking"
            linear = min(self.path.speed, remaining / dt)
            angular = max(-MAX_TURN, min(MAX_TURN, error / dt)) if linear == self.path.speed else 0.0
            return linear, angular
        return 0.0, 0.0

    def _waiting_for(self, now: float) -> str:
        """What the person still waits for at its waypoint ("" once nothing)."""
        point = self.target
        left = self._arrived_at + point.wait - now
        if left > 1e-9:
            return f"{left:.1f} s"
        if point.until_near is not None:
            distance = self._distance_to(point.until_near)
            if distance is not None and distance > point.within:
                return f"{point.until_near} within {point.within:g} m"
        if point.until_message is not None and point.until_message not in self._heard:
            return f"message {point.until_message!r}"
        return ""

    def _next(self) -> None:
        """Set off toward the next waypoint (or stand: the path is walked)."""
        last = len(self.path.waypoints) - 1
        if self.index == last and not self.path.loop:
            self.state = "done"
            return
        self.index = 0 if self.index == last else self.index + 1
        self.laps += self.index == 0
        self.state = "turning"
        self._heard.clear()


# ---------------------------------------------------------------------------------------------- what is wrong
@dataclass(frozen=True)
class Problem:
    """Why a path cannot be walked: at ``waypoint`` (0-based; a leg's problem is at the waypoint it leads to), in
    its ``attribute`` (None: the waypoint as a whole), ``what``."""

    waypoint: int
    attribute: str | None
    what: str

    def __str__(self) -> str:
        return f"waypoint {self.waypoint}{f' {self.attribute}' if self.attribute else ''}: {self.what}"


RayHits = Callable[[np.ndarray, np.ndarray, float, Sequence[str]], tuple[np.ndarray, list[str | None]]]
""":meth:`sigcore.backend.Backend.ray_hits`."""


def path_problems(person: Human, path: WalkPath, start: tuple[float, float], entities: Sequence[Entity],
                  positions: Callable[[str], tuple[float, float]], ray_hits: RayHits) -> list[Problem]:
    """What makes ``path`` impossible for ``person`` standing at ``start`` (x, y [m]), none when it can be walked.

    Args:
        person: The person (its height sets the rays' heights).
        path: The path.
        start: Where the person stands when it sets off.
        entities: The world's entities now (names, which are static).
        positions: Where an entity is now (x, y) [m].
        ray_hits: The backend's :meth:`~sigcore.backend.Backend.ray_hits`.
    """
    problems: list[Problem] = []
    names = {e.name: e for e in entities}
    static = [e.name for e in entities if isinstance(e, Object) and e.static]
    points = [(w.x, w.y) for w in path.waypoints]
    legs = list(zip([start, *points[:-1]], points, strict=True))
    if path.loop and len(points) > 1:
        legs.append((points[-1], points[0]))
    heights = np.array(_RAY_HEIGHTS) * person.height / 1.7
    for i, ((x0, y0), (x1, y1)) in enumerate(legs):
        length = math.hypot(x1 - x0, y1 - y0)
        if length < 1e-9 or not static:
            continue
        direction = np.array([[(x1 - x0) / length, (y1 - y0) / length, 0.0]])
        for z in heights:
            distance, hit = ray_hits(np.array([x0, y0, z]), direction, length, static)
            if hit[0] is not None:
                at = (x0 + direction[0, 0] * distance[0], y0 + direction[0, 1] * distance[0])
                came = "the start" if i == 0 else f"waypoint {i - 1}"
                problems.append(Problem(i % len(points), None, f"the leg from {came} ({x0:g}, {y0:g}) to ({x1:g}, "
                                        f"{y1:g}) passes through the static '{hit[0]}' at ({at[0]:.2f}, "
                                        f"{at[1]:.2f}), {z:.2f} m up; a person walks straight between waypoints: "
                                        "add a waypoint around it"))
                break
    for i, point in enumerate(path.waypoints):
        near = point.until_near
        if near is None:
            continue
        entity = names.get(near)
        if entity is None or near == person.name:
            what = "the person itself" if near == person.name else f"no entity '{near}'"
            problems.append(Problem(i, "until_near", f"{what}; valid: another entity: "
                                                     f"{', '.join(n for n in names if n != person.name) or 'none'}"))
        elif isinstance(entity, Object) and entity.static:
            ex, ey = positions(near)
            gap = math.hypot(ex - point.x, ey - point.y)
            if gap > point.within:
                problems.append(Problem(i, "until_near", f"'{near}' within {point.within:g} m can never hold: "
                                                         f"'{near}' is static, {gap:.2f} m from the waypoint "
                                                         f"({point.x:g}, {point.y:g})"))
    return problems
