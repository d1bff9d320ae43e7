"""The topics a transport subscribes for each person (``<human>``): ``/<person>/cmd_vel`` (a walk by velocity),
``/<person>/path`` (a path to walk) and ``/<person>/skeleton`` (joint angles and the root's pose). Each message goes
through ``sim.inputs`` (so that recordings replay it); what is refused is logged with what was wrong
(docs/people.md)."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from geometry_msgs.msg import Twist
from nav_msgs.msg import Path
from pydantic import ValidationError
from sensor_msgs.msg import JointState

from sigcore.agent.exceptions import ApiError
from sigcore.api.call import log_key
from sigcore.sim.frames import WORLD
from sigcore.text import clip
from sigcore.transport import Endpoint
from sigcore.world.models import WalkPath, Waypoint

from .qos import Qos

if TYPE_CHECKING:
    from rclpy.node import Node

    from sigcore.sim import Simulation

    from .receiver import Receiver

log = logging.getLogger("sigcore.ros2")

WALK_TIMEOUT = 0.5
"""A person walked by ``/<person>/cmd_vel`` stands again after this long without a message [s of simulated time]
(as a robot's drive with the default ``cmd_vel_timeout``)."""
PATH_SPEED = 1.0
"""The speed a person walks a ``/<person>/path`` at when its world file gives it no ``<path speed>`` [m/s]."""


class PeopleTopics:
    """The people's subscribed topics (see the module docstring).

    Args:
        sim: The simulation.
        node: The node that owns the subscriptions.
        receiver: Where they are registered (their messages are handled on the simulation's thread).
        qos: QoS profiles.
        topics: The transport's topic table (name -> type), which this adds to and removes from.
    """

    def __init__(self, sim: Simulation, node: Node, receiver: Receiver, qos: Qos, topics: dict[str, str]) -> None:
        self.sim, self.node, self.receiver, self.qos, self.topics = sim, node, receiver, qos, topics
        self.subs: dict[str, list[Any]] = {}
        self._owned: dict[str, list[str]] = {}  # person -> its topics
        self._walk_deadline: dict[str, int] = {}  # person -> step at which its cmd_vel times out

    @property
    def owners(self) -> tuple[str, ...]:
        """The people that have topics here."""
        return tuple(self._owned)

    def add(self, people: list[str]) -> None:
        """Create ``/<person>/cmd_vel`` (geometry_msgs/Twist), ``/<person>/path`` (nav_msgs/Path) and
        ``/<person>/skeleton`` (sensor_msgs/JointState) of each of ``people``. A Twist walks the person
        (``sim.inputs.person_velocity``), which stands again when no message came for :data:`WALK_TIMEOUT` s of
        simulated time; a Path has it walk through the poses' positions (``sim.inputs.person_path``) at its
        ``<path>``'s speed, or :data:`PATH_SPEED`; a JointState poses its joints and feet frame
        (``sim.inputs.person_joints``)."""
        for name in people:
            ns = self.sim.entities.namespace(name)
            topic = f"{ns}/{name}/cmd_vel"
            sub = self.node.create_subscription(Twist, topic, lambda *_: None, self.qos.commands(topic))
            self.receiver.add_subscription(sub, self._walk(name, topic))
            self.subs[name] = [sub]
            self.topics[topic] = "geometry_msgs/msg/Twist"
            path_topic = f"{ns}/{name}/path"
            sub = self.node.create_subscription(Path, path_topic, lambda *_: None, self.qos.commands(path_topic))
            self.receiver.add_subscription(sub, self._path(name, path_topic))
            self.subs[name].append(sub)
            self.topics[path_topic] = "nav_msgs/msg/Path"
            skeleton = f"{ns}/{name}/skeleton"
            sub = self.node.create_subscription(JointState, skeleton, lambda *_: None, self.qos.commands(skeleton))
            self.receiver.add_subscription(sub, self._skeleton(name, skeleton))
            self.subs[name].append(sub)
            self.topics[skeleton] = "sensor_msgs/msg/JointState"
            self._owned.setdefault(name, []).extend([topic, path_topic, skeleton])

    def _skeleton(self, person: str, topic: str) -> Any:
        """The handler of ``/<person>/skeleton``: ``name`` and ``position`` of the same length, each name a
        REP-155 joint of the person or one of ``root_x`` ... ``root_yaw`` (``velocity`` and ``effort`` unused)."""

        def handle(msg: JointState) -> None:
            names, positions = list(msg.name), list(msg.position)
            try:
                if len(names) != len(positions):
                    raise ApiError(f"{len(names)} names and {len(positions)} positions; valid: one position per "
                                   "name")
                twice = sorted({n for n in names if names.count(n) > 1})
                if twice:
                    raise ApiError(f"{', '.join(twice[:5])} named twice; valid: each joint once")
                self._walk_deadline.pop(person, None)  # a cmd_vel's timeout must not stand it up again
                self.sim.inputs.person_joints(person, dict(zip(names, positions, strict=True)))
            except ApiError as e:
                log.warning("%s refused: %s", topic, clip(str(e)), extra=log_key(topic, type(e).__name__))

        return handle

    def _path(self, person: str, topic: str) -> Any:
        """The handler of ``/<person>/path``."""

        def handle(msg: Path) -> None:
            try:
                path = self._walk_path(person, msg)
                self.sim.inputs.person_path(person, path)
            except ApiError as e:
                log.warning("%s refused: %s", topic, clip(str(e)), extra=log_key(topic, type(e).__name__))
                return
            self._walk_deadline.pop(person, None)  # a cmd_vel's timeout must not stop the path

        return handle

    def _walk_path(self, person: str, msg: Path) -> WalkPath:
        """The :class:`WalkPath` of a nav_msgs/Path for ``person``.

        Raises:
            ApiError: a frame other than the world's, no poses, a position that is not finite or out of range.
        """
        frame = msg.header.frame_id
        if frame not in ("", WORLD):
            raise ApiError(f"a path in frame '{clip(frame, 40)}'; valid: '{WORLD}' (or empty): the positions are "
                           "the world's")
        if not msg.poses:
            raise ApiError("a path with no poses; valid: one or more, walked in order (their positions' x and y)")
        own = self.sim.entities.people.model(person).path
        try:
            points = tuple(Waypoint(x=p.pose.position.x, y=p.pose.position.y) for p in msg.poses)
            return WalkPath(speed=own.speed if own is not None else PATH_SPEED, waypoints=points)
        except ValidationError as e:
            first = e.errors()[0]
            where = ".".join(str(v) for v in first["loc"])
            raise ApiError(f"a path's poses: {where}: {first['msg']} (got {first.get('input')!r})") from None

    def _walk(self, person: str, topic: str) -> Any:
        """The handler of ``/<person>/cmd_vel``."""
        steps = max(1, round(WALK_TIMEOUT / self.sim.dt))

        def handle(msg: Twist) -> None:
            try:
                self.sim.inputs.person_velocity(person, msg.linear.x, msg.angular.z)
            except ApiError as e:  # the transport's log filter lets one record per (topic, kind) through
                log.warning("%s refused: %s", topic, clip(str(e)), extra=log_key(topic, type(e).__name__))
                return
            self._walk_deadline[person] = self.sim.step_count + steps

        return handle

    def remove(self, names: list[str]) -> None:
        """Destroy the topics of the people among ``names`` (deleted while running)."""
        for name in names:
            for topic in self._owned.pop(name, []):
                self.topics.pop(topic, None)
            for sub in self.subs.pop(name, []):
                if self.receiver.retire([sub]):
                    self.node.destroy_subscription(sub)
            self._walk_deadline.pop(name, None)

    def on_step(self, n: int) -> None:
        """After step ``n``: a person whose ``cmd_vel`` stopped coming :data:`WALK_TIMEOUT` ago stands."""
        if self._walk_deadline:
            for name in [p for p, step in self._walk_deadline.items() if n >= step]:
                del self._walk_deadline[name]
                if name in self.sim.entities:
                    self.sim.inputs.person_velocity(name, 0.0, 0.0)

    @staticmethod
    def plan(sim: Simulation) -> list[Endpoint]:
        """The topics :meth:`add` creates for the world's people, without creating any."""
        out = []
        for name in sim.entities.people.names:
            out.append(Endpoint(f"/{name}/cmd_vel", "geometry_msgs/msg/Twist", "topic",
                                f"the walk of human '{name}' (linear.x, angular.z)", name, "name"))
            out.append(Endpoint(f"/{name}/path", "nav_msgs/msg/Path", "topic",
                                f"a path for human '{name}' to walk (the poses' x, y)", name, "name"))
            out.append(Endpoint(f"/{name}/skeleton", "sensor_msgs/msg/JointState", "topic",
                                f"the joints (REP-155 names) and root pose of human '{name}'", name, "name"))
        return out
