"""What moves the people of a world (``sim.entities.people``): the one owner of each person's motion source.

A person (``<human>``) is held kinematically by the backend (:mod:`sigcore.world.body`); something must move it.
Each person has at most one motion source at a time, the last one given (a walk by velocity ends a path, a path
ends a walk by velocity):

* **walking by velocity** (:meth:`People.walk`, ``/<person>/cmd_vel``);
* **walking a path** (:meth:`People.follow`, ``<path>`` in the world file, ``/<person>/path``): a
  :class:`~sigcore.sim.paths.PathWalker` gives the velocity at each step;
* **a skeleton** (:meth:`People.set_joints`, ``/<person>/skeleton``, the API's ``_setJointAngle``): joint angles
  and the root's pose, put in place at once (the Kinect avatar's successor).

The walks drive a procedural gait (:mod:`sigcore.sim.gait`) that puts the feet frame and every joint where the gait has
them after each step, in simulated time. Nothing is done for a person that stands (no step subscriber is due then,
so the core's batched steps stay batched).

Commands from outside (a transport, a viewer) go through ``sim.inputs.person_velocity``,
``sim.inputs.person_path`` and ``sim.inputs.person_joints``, so that a recording replays them
(:mod:`sigcore.sim.inputs`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from ..agent.events import Message
from ..agent.exceptions import ApiError
from ..errors import BackendError
from ..geometry import angle_about, quat_from_rpy, quat_to_rpy, quat_yaw
from ..text import quote
from ..world.body import Body, human_body
from ..world.exceptions import WorldError, WorldIssue
from ..world.limits import MAX_COORDINATE
from ..world.models import Entity, Human, WalkPath, World
from .gait import Gait
from .paths import PathWalker, Problem, Progress, path_problems

if TYPE_CHECKING:
    from .events import Subscription
    from .simulation import Simulation

log = logging.getLogger("sigcore.people")

ROOT_POSE = ("root_x", "root_y", "root_z", "root_roll", "root_pitch", "root_yaw")
"""The names that set a person's feet frame in :meth:`People.set_joints` (x, y, z [m], roll, pitch, yaw [rad], in
the world), beside its joints' REP-155 names."""


class People:
    """The people of the running world and their motion (see the module docstring).

    Args:
        sim: The simulation (its backend built).
        world: The world (the people among its entities are kept; their ``<path>`` is walked from the start).
        now: The world as it is now (spawned entities in, deleted ones out).

    Raises:
        WorldError: a ``<path>`` of the world file cannot be walked (:func:`~sigcore.sim.paths.path_problems`),
            located at its waypoint.
    """

    def __repr__(self) -> str:
        return "<the people's motion>"

    def __init__(self, sim: Simulation, world: World, now: Callable[[], World]) -> None:
        self._sim = sim
        self._now = now
        self._bodies: dict[str, Body] = {}
        self._models: dict[str, Human] = {}
        self._gaits: dict[str, Gait] = {}
        self._walkers: dict[str, PathWalker] = {}
        self._stepping: Subscription | None = None  # subscribed when someone first walks: a world pays nothing before
        self._hearing: Subscription | None = None
        self._gone: set[tuple[str, str]] = set()
        self.add(world.entities, world)

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

    def model(self, person: str) -> Human:
        """The ``<human>`` of ``person``; ``ApiError`` listing the people otherwise."""
        self.body(person)
        return self._models[person]

    def walk(self, person: str, linear: float, angular: float) -> None:
        """Walk ``person`` at ``linear`` [m/s] forward (negative: backward) turning at ``angular`` [rad/s], from the
        next step on, until told otherwise (0, 0: it finishes its step and stands). A path it walked ends.

        Raises:
            ApiError: no such person, or a value out of range or not finite (the message names the valid range);
                nothing changes then.
        """
        gait = self._gait(person)
        try:
            gait.command(float(linear), float(angular))
        except (TypeError, ValueError) as e:
            raise ApiError(f"walking {quote(person)}: {e}") from None
        self._gaits[person] = gait
        self._walkers.pop(person, None)
        self._stepped()

    def follow(self, person: str, path: WalkPath) -> None:
        """Walk ``person`` along ``path`` from the next step on (:mod:`sigcore.sim.paths`), from where it is; a walk
        by velocity or another path it walked ends.

        Raises:
            ApiError: no such person, or the path cannot be walked (each waypoint's problem named); nothing changes
                then.
        """
        self.body(person)
        if not isinstance(path, WalkPath):
            raise ApiError(f"a path for {quote(person)} must be a WalkPath, got {type(path).__name__}")
        x, y = self._where(person)
        problems = self._problems(self._models[person], path, (x, y))
        if problems:
            raise ApiError(f"{quote(person)} cannot walk this path: " + "; ".join(map(str, problems)))
        self._start(person, path)

    def set_joints(self, person: str, positions: Mapping[str, float]) -> None:
        """Put ``person``'s joints at ``positions`` [rad] by REP-155 name (``l_elbow``, ``r_p_shoulder``; the
        joints not named keep their angles) and, with names of :data:`ROOT_POSE`, its feet frame there (those not
        named keep their values), at once: the next step shows it. A walk or a path it had ends, at once.

        Raises:
            ApiError: an unknown name, a value that is not a finite number or is outside the joint's limits (each
                message names what is valid); nothing changes then.
        """
        body = self.body(person)
        joints = {j.name: j for j in body.joints if j.type == "revolute"}
        angles: dict[str, float] = {}
        root: dict[str, float] = {}
        for name, value in positions.items():
            joint = joints.get(name)
            if joint is None and name not in ROOT_POSE:
                raise ApiError(f"{quote(person)} has no joint {quote(str(name))}; valid: its REP-155 joints "
                               f"{', '.join(joints)}, and {', '.join(ROOT_POSE)} for its feet frame")
            try:
                v = float(value)
            except (TypeError, ValueError):
                raise ApiError(f"{name} of {quote(person)}: {value!r} is not a number") from None
            if not math.isfinite(v) or abs(v) > MAX_COORDINATE:
                raise ApiError(f"{name} of {quote(person)}: {v!r}; valid: a finite number")
            if joint is not None and not joint.lower - 1e-9 <= v <= joint.upper + 1e-9:
                raise ApiError(f"joint {quote(name)} of {quote(person)} turns from {joint.lower:g} to "
                               f"{joint.upper:g} rad, got {v:g}")
            (angles if joint is not None else root)[name] = v
        self._walkers.pop(person, None)
        self._gaits.pop(person, None)
        backend = self._sim.backend
        if root:
            pos, quat = backend.get_pose(person)
            now = dict(zip(ROOT_POSE, (*(float(v) for v in pos), *quat_to_rpy(quat)), strict=True))
            now.update(root)
            x, y, z, roll, pitch, yaw = (now[k] for k in ROOT_POSE)
            backend.set_pose(person, np.array([x, y, z]), quat_from_rpy(roll, pitch, yaw))
        if angles:
            backend.set_joint_angles(person, angles)

    def joint_quaternion(self, person: str, joint: str, wxyz: Sequence[float], offset: bool = False) -> float:
        """The angle [rad] that ``_setJointQuaternion`` gives ``person``'s ``joint``: the twist of ``wxyz`` about
        the joint's axis (added to its angle now with ``offset``).

        Raises:
            ApiError: no such person or joint, or a zero or non-finite quaternion.
        """
        joints = {j.name: j for j in self.body(person).joints if j.type == "revolute"}
        if joint not in joints:
            raise ApiError(f"{quote(person)} has no joint {quote(joint)}; valid: {', '.join(joints)}")
        q = np.asarray([float(v) for v in wxyz], dtype=float)
        if q.shape != (4,) or not np.isfinite(q).all() or float(np.linalg.norm(q)) < 1e-9:
            raise ApiError(f"quaternion {tuple(q.tolist())} of {quote(person)}'s {quote(joint)}; valid: 4 finite "
                           "numbers qw qx qy qz, not all zero, e.g. 1 0 0 0")
        angle = angle_about(joints[joint].axis, q)
        return angle + self._sim.backend.get_joint_angle(person, joint) if offset else angle

    def progress(self, person: str) -> Progress | None:
        """Where ``person`` is on the path it walks (None: it walks no path; a walked path's last state stays
        until another motion starts)."""
        self.body(person)
        walker = self._walkers.get(person)
        return walker.progress() if walker is not None else None

    def _start(self, person: str, path: WalkPath) -> None:
        self._walkers[person] = PathWalker(path, partial(self._distance, person))
        gait = self._gaits.pop(person, None)
        if gait is not None:  # the walk by velocity ends: the path's commands take over from the next step
            gait.command(0.0, 0.0)
            self._gaits[person] = gait
        if self._hearing is None and any(w.until_message for w in path.waypoints):
            self._hearing = self._sim.events.subscribe("message", self._on_message, owner=self)
        self._stepped()

    def _stepped(self) -> None:
        if self._stepping is None:
            self._stepping = self._sim.events.subscribe("step", self._on_step, owner=self)
        self._stepping.set_every(1)

    def _gait(self, person: str) -> Gait:
        """``person``'s gait, made where it stands when it is not walking."""
        body = self.body(person)
        gait = self._gaits.get(person)
        if gait is None:
            pos, quat = self._sim.backend.get_pose(person)
            gait = Gait(body, float(pos[0]), float(pos[1]), float(pos[2]), quat_yaw(quat))
        return gait

    def _where(self, name: str) -> tuple[float, float]:
        gait = self._gaits.get(name)
        if gait is not None:
            return gait.x, gait.y
        pos = self._sim.backend.get_pose(name)[0]
        return float(pos[0]), float(pos[1])

    def _distance(self, person: str, other: str) -> float | None:
        """The distance [m] on the floor from ``person`` to ``other``; None once ``other`` is gone (a condition
        on it counts as met, with a warning)."""
        if other not in self._sim.entities:  # checked each step while it waits: a dict look-up
            if (person, other) not in self._gone:
                self._gone.add((person, other))
                log.warning("'%s' waits for '%s' to come near, which is gone: it walks on", person, other)
            return None
        x, y = self._where(person)
        ox, oy = self._where(other)
        return math.hypot(ox - x, oy - y)

    def _problems(self, person: Human, path: WalkPath, start: tuple[float, float]) -> list[Problem]:
        entities = self._now().entities
        try:
            return path_problems(person, path, start, entities, self._where, self._sim.backend.ray_hits)
        except BackendError as e:  # a backend that cannot tell what a ray hits: no check of the legs
            log.warning("the legs of %s's path are not checked against walls: %s", person.name, e)
            return []

    def refusal(self, entities: Sequence[Entity]) -> str | None:
        """Why people about to be spawned cannot walk their ``<path>`` (None: they can)."""
        for e in entities:
            if isinstance(e, Human) and e.path is not None:
                problems = self._problems(e, e.path, (e.pose.xyz[0], e.pose.xyz[1]))
                if problems:
                    return f"{quote(e.name)} cannot walk its <path>: " + "; ".join(map(str, problems))
        return None

    def _on_message(self, msg: Message) -> None:
        walker = self._walkers.get(msg.to)
        if walker is not None:
            walker.hear(msg.content)

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
        backend, dt, now = self._sim.backend, self._sim.dt, self._sim.time
        for name, walker in self._walkers.items():
            if walker.state != "done":
                gait = self._gaits[name] = self._gait(name)
                gait.command(*walker.command(gait.x, gait.y, gait.yaw, now, dt))
        for name, gait in list(self._gaits.items()):
            posture = gait.advance(dt)
            backend.set_pose(name, np.array([posture.x, posture.y, posture.z]), quat_from_rpy(0.0, 0.0, posture.yaw))
            backend.set_joint_angles(name, posture.angles)
            if not gait.moving and not self._walking_on(name):
                del self._gaits[name]  # it stands: the next walk starts from where it is then
        if not self._gaits and not any(self._walking_on(n) for n in self._walkers) and self._stepping is not None:
            self._stepping.set_every(0)

    def _walking_on(self, name: str) -> bool:
        """Whether ``name`` has a path still to walk (waiting counts: its conditions are checked every step)."""
        walker = self._walkers.get(name)
        return walker is not None and walker.state != "done"

    # ------------------------------------------------------------------ entities come and go
    def add(self, entities: Iterable[Entity], world: World | None = None) -> None:
        """People spawned (or the ``world``'s, at start): each walks its ``<path>`` from the next step.

        Raises:
            WorldError: at start, a ``<path>`` that cannot be walked, located at its waypoint in ``world``'s file.
        """
        people = [e for e in entities if isinstance(e, Human)]
        for e in people:
            self._bodies[e.name] = human_body(e.height, e.mass)
            self._models[e.name] = e
        issues: list[WorldIssue] = []
        for e in people:
            if e.path is None:
                continue
            problems = self._problems(e, e.path, (e.pose.xyz[0], e.pose.xyz[1]))
            if problems and world is not None:
                for p in problems:
                    key = f"waypoint:{p.waypoint}" + (f":{p.attribute}" if p.attribute else "")
                    line, column = world.location(e.name, key)
                    issues.append(WorldIssue(world.source, line, column, "waypoint", p.attribute, p.what))
            elif problems:
                log.warning("%s does not walk its <path>: %s", e.name, "; ".join(map(str, problems)))
            else:
                self._start(e.name, e.path)
        if issues:
            raise WorldError(sorted(issues, key=lambda i: (i.line, i.column)))

    def remove(self, names: Iterable[str]) -> None:
        """People deleted: their motion stops with them."""
        for name in names:
            self._bodies.pop(name, None)
            self._models.pop(name, None)
            self._gaits.pop(name, None)
            self._walkers.pop(name, None)

    def reset(self) -> None:
        """Everyone stands where a reset put them, or walks its ``<path>`` again from the start."""
        self._gaits.clear()
        self._walkers.clear()
        self._gone.clear()
        if self._stepping is not None:
            self._stepping.set_every(0)
        for name, model in self._models.items():
            if model.path is not None:
                self._start(name, model.path)

    def close(self) -> None:
        """The world goes: the step subscription is detached."""
        self._sim.events.detach(self)

