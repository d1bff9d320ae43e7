"""Idiomatic ROS 2 topics: /clock, /tf, and per robot cmd_vel, odom, joint_states, LaserScans.

Frames (REP-105) are named and computed by the core (:class:`sigcore.sim.frames.Frames`): with one robot, ``odom``
and the URDF's link names (e.g. ``base_link``); with several, each robot's frames are prefixed with ``<robot>/``;
objects and humans by their names. On /tf, in one message per state publication with one stamp: ``odom ->
base_link`` (wheel odometry), every movable joint, the root link of a free robot; in another, at
``entity_tf_rate``, ``world -> <entity>`` of every object and human. The static part of the tree (``world ->
odom``, fixed joints) is the core's ``/tf_static`` publication. The people's topics (cmd_vel, path, skeleton) are
:class:`~.people.PeopleTopics`'.
"""

from __future__ import annotations

import logging
import math
import time
from typing import TYPE_CHECKING, Any

from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState, LaserScan
from tf2_msgs.msg import TFMessage

from sigcore.agent.exceptions import ApiError
from sigcore.agent.robot import RobotObj
from sigcore.api.call import log_key
from sigcore.sim.frames import WORLD
from sigcore.sim.lidar import Scan
from sigcore.sim.odometry_covariance import odometry_covariance
from sigcore.text import clip
from sigcore.transport import Endpoint

from .cdr import CdrTemplate
from .convert import offered
from .people import PeopleTopics
from .publications import fill_message
from .qos import Qos

if TYPE_CHECKING:
    from rclpy.node import Node

    from sigcore.sim.simulation import Simulation

    from .config import Ros2Config
    from .receiver import Receiver

log = logging.getLogger("sigcore.ros2")



class StandardEndpoints:
    """/clock, /tf and the per-robot topics; published by a step observer.

    Args:
        sim: The simulation.
        node: The node that owns the endpoints.
        receiver: Where the cmd_vel subscriptions are registered.
        qos: QoS profiles.
        config: Rates.
    """

    def __init__(self, sim: Simulation, node: Node, receiver: Receiver, qos: Qos, config: Ros2Config) -> None:
        self.sim = sim
        self.config = config
        # the /clock policy: every clock_every steps but at most one per clock_gap [s] of wall time, except that a
        # step whose state or scan is published always has its /clock first (docs/ros2.md, "The /clock policy")
        self.clock_gap = 1.0 / config.clock_wall_limit if config.clock_wall_limit > 0 else 0.0
        self._timing()
        self.entity_rate = config.entity_tf_rate
        self.entity_every = 0
        self.node, self.receiver, self.qos = node, receiver, qos
        self.clock_pub = node.create_publisher(Clock, "/clock", qos.clock())
        self._clock = CdrTemplate(Clock(), ["clock.sec", "clock.nanosec"])
        self.tf_pub = node.create_publisher(TFMessage, "/tf", qos.tf())
        self.topics: dict[str, str] = {"/clock": "rosgraph_msgs/msg/Clock", "/tf": "tf2_msgs/msg/TFMessage"}
        self.prefix: dict[str, str] = {}
        self.base: dict[str, str] = {}
        self.odom_pub: dict[str, Any] = {}
        self.joint_pub: dict[str, Any] = {}
        self.joints: dict[str, list[str]] = {}
        self.scan_pub: dict[tuple[str, str], Any] = {}
        self.cmd_vel_sub: dict[str, Any] = {}
        self.people = PeopleTopics(sim, node, receiver, qos, self.topics)
        self._owned: dict[str, list[str]] = {}  # robot -> its topics
        self._timed_out: set[str] = set()  # robots whose cmd_vel timeout was logged (once each)
        self._cmd_vel_deadline: dict[str, int] = {}  # robot -> step at which its cmd_vel times out
        self.add([h.name for h in sim.entities.values() if isinstance(h, RobotObj)])
        self.add_people(list(sim.entities.people.names))
        sim.events.subscribe("scan", self._scan)

    def _timing(self) -> None:
        """The step counts of the rates for the world's timestep (at start, and for each world loaded)."""
        dt, config = self.sim.dt, self.config
        self.dt_ns = round(dt * 1e9)
        self.clock_every = 1 if config.clock_rate <= 0 else max(1, round(1.0 / (config.clock_rate * dt)))
        self.state_every = max(1, round(1.0 / (config.state_rate * dt)))
        self._next_clock = 0.0
        self.clock_step = -1

    def world_loaded(self) -> None:
        """A world was loaded (the old one's robots were removed when it was unloading): the rates follow its
        timestep, /clock starts again at its time 0, its robots get their topics."""
        self._timing()
        self.add([h.name for h in self.sim.entities.values() if isinstance(h, RobotObj)])
        self.add_people(list(self.sim.entities.people.names))

    # ------------------------------------------------------------------ entities added and removed
    def add(self, robots: list[str]) -> None:
        """Create the topics of ``robots`` (the world's at start, or robots added while running, each under its
        namespace ``sim.entities.namespace(robot)``), then rebuild the state messages."""
        sim, node, qos = self.sim, self.node, self.qos
        for name in robots:
            robot = sim.robot(name)
            ns = sim.entities.namespace(name)
            own = self._owned.setdefault(name, [])
            self.prefix[name] = sim.frames.prefix(name)
            self.base[name] = self.prefix[name] + sim.entities.urdf(name).root
            self.joints[name] = [j.name for j in sim.entities.urdf(name).movable_joints]
            topic = f"{ns}/{name}/joint_states"
            self.joint_pub[name] = node.create_publisher(JointState, topic, qos.state(topic))
            self.topics[topic] = "sensor_msgs/msg/JointState"
            own.append(topic)
            if sim.entities.robot_model(name).drive is not None:
                sim.entities.enable_odometry(name)
                topic = f"{ns}/{name}/odom"
                self.odom_pub[name] = node.create_publisher(Odometry, topic, qos.state(topic))
                self.topics[topic] = "nav_msgs/msg/Odometry"
                own.append(topic)
                topic = f"{ns}/{name}/cmd_vel"
                sub = node.create_subscription(Twist, topic, lambda *_: None, qos.commands(topic))
                self.receiver.add_subscription(sub, self._cmd_vel(robot, topic))
                self.cmd_vel_sub[name] = sub
                self.topics[topic] = "geometry_msgs/msg/Twist"
                own.append(topic)
            for lidar in sim.entities.lidars:
                if lidar.robot == name:
                    topic = f"{ns}/{lidar.robot}/{lidar.model.name}"
                    self.scan_pub[(lidar.robot, lidar.model.name)] = node.create_publisher(LaserScan, topic,
                                                                                           qos.sensor(topic))
                    self.topics[topic] = "sensor_msgs/msg/LaserScan"
                    own.append(topic)
        self.rebuild()

    @property
    def owners(self) -> tuple[str, ...]:
        """The robots and people that have topics here."""
        return (*self._owned, *self.people.owners)

    def add_people(self, people: list[str]) -> None:
        """Create the topics of ``people`` (:class:`~.people.PeopleTopics`)."""
        self.people.add(people)

    def remove(self, robots: list[str]) -> None:
        """Destroy the topics of ``robots`` (deleted while running), then rebuild the state messages."""
        node = self.node
        self.people.remove(robots)
        for name in robots:
            for topic in self._owned.pop(name, []):
                self.topics.pop(topic, None)
            sub = self.cmd_vel_sub.pop(name, None)
            if sub is not None and self.receiver.retire([sub]):
                node.destroy_subscription(sub)
            for pubs in (self.joint_pub, self.odom_pub):
                pub = pubs.pop(name, None)
                if pub is not None:
                    node.destroy_publisher(pub)
            for key in [k for k in self.scan_pub if k[0] == name]:
                node.destroy_publisher(self.scan_pub.pop(key))
            for table in (self.prefix, self.base, self.joints):
                table.pop(name, None)
            self._cmd_vel_deadline.pop(name, None)
            self._timed_out.discard(name)
        self.rebuild()

    def rebuild(self) -> None:
        """Serialize the state messages once for the robots and entities there are now (each publication only
        rewrites their numbers): at start and after each change of the entities."""
        sim = self.sim
        frames = sim.frames
        for name in self.joints:  # a robot's frame prefix depends on how many robots there are
            self.prefix[name] = frames.prefix(name)
            self.base[name] = self.prefix[name] + sim.entities.urdf(name).root
        rate = self.entity_rate
        self.entity_every = 0 if rate <= 0 or not frames.entities else max(1, round(1.0 / (rate * sim.dt)))
        moving = [name for name in sim.entities.odometry if name in self.odom_pub]
        self._odom = [(sim.entities.odometry[name], self.odom_pub[name],
                       _odometry(self.prefix[name] + "odom", self.base[name], *self._covariance(name)),
                       frames.root_mode(name) == "odom") for name in moving]
        # one /tf message: odom -> root of each robot under its odometry, then each robot's joints (Frames.moving)
        pairs = [(self.prefix[odo.robot] + "odom", self.base[odo.robot]) for odo, _, _, tf in self._odom if tf]
        pairs += [pair for name in self.joints for pair in frames.moving(name)]
        self._people = frames.people
        pairs += [pair for name in self._people for pair in frames.moving(name)]
        self._tf = _transforms(pairs) if pairs else None
        self._joint_states = [(name, joints, self.joint_pub[name], _joint_state(joints), bool(frames.moving(name)))
                              for name, joints in self.joints.items()]
        self._entity_tf = _transforms([(WORLD, e) for e in frames.entities]) if self.entity_every else None

    @staticmethod
    def plan(sim: Simulation) -> list[Endpoint]:
        """Every topic the constructor creates, with the world element that brought its name in, without creating
        any."""
        out = [Endpoint("/clock", "rosgraph_msgs/msg/Clock", "topic", "the transport's clock"),
               Endpoint("/tf", "tf2_msgs/msg/TFMessage", "topic",
                        "the transport's odometry, joint and entity transforms", shared=True)]
        for name, handle in sim.entities.items():
            if isinstance(handle, RobotObj):
                out.append(Endpoint(f"/{name}/joint_states", "sensor_msgs/msg/JointState", "topic",
                                    f"the joint states of robot '{name}'", name, "name"))
                if sim.entities.robot_model(name).drive is not None:
                    what = f"of the <drive> of robot '{name}'"
                    out.append(Endpoint(f"/{name}/odom", "nav_msgs/msg/Odometry", "topic", f"the odometry {what}",
                                        name, "drive", "drive"))
                    out.append(Endpoint(f"/{name}/cmd_vel", "geometry_msgs/msg/Twist", "topic",
                                        f"the cmd_vel {what}", name, "drive", "drive"))
        out.extend(PeopleTopics.plan(sim))
        for lidar in sim.entities.lidars:
            out.append(Endpoint(f"/{lidar.robot}/{lidar.model.name}", "sensor_msgs/msg/LaserScan", "topic",
                                f"the scans of <lidar name='{lidar.model.name}'> of robot '{lidar.robot}'",
                                lidar.robot, f"lidar:{lidar.model.name}", "lidar"))
        return out

    def _covariance(self, robot: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The pose and twist covariance diagonals of ``robot``'s odometry, from its world file's ``<drive>`` and the
        odometry's noise (:mod:`sigcore.sim.odometry_covariance`)."""
        drive = self.sim.entities.robot_model(robot).drive
        assert drive is not None
        return odometry_covariance(drive.radius, drive.separation, drive.max_wheel_velocity,
                                   self.sim.entities.odometry[robot].noise)

    # ------------------------------------------------------------------ incoming
    def _cmd_vel(self, robot: RobotObj, topic: str) -> Any:
        """The handler of ``[/ns]/<robot>/cmd_vel`` (``topic``): drive, and stop again after the drive's
        ``cmd_vel_timeout`` of simulated time without a new accepted message (0: never), like ros2_control's
        diff_drive_controller."""
        timeout = self.sim.entities.drive(robot.name).cmd_vel_timeout
        steps = max(1, round(timeout / self.sim.dt)) if timeout > 0 else 0

        def handle(msg: Twist) -> None:
            try:
                self.sim.inputs.base_velocity(robot.name, msg.linear.x, msg.angular.z)
            except ApiError as e:  # the transport's log filter lets one record per (topic, kind) through
                log.warning("%s refused: %s", topic, clip(str(e)), extra=log_key(topic, type(e).__name__))
                return
            if steps:
                self._cmd_vel_deadline[robot.name] = self.sim.step_count + steps

        return handle

    def _stop_stale_cmd_vel(self, step: int) -> None:
        """Stop the wheels of each robot whose last cmd_vel is ``cmd_vel_timeout`` old (a crashed client must not
        leave its robot driving)."""
        for name, deadline in list(self._cmd_vel_deadline.items()):
            if step >= deadline:
                del self._cmd_vel_deadline[name]
                self.sim.inputs.wheel_velocity(name, 0.0, 0.0)
                if name not in self._timed_out:
                    self._timed_out.add(name)
                    log.info("/%s/cmd_vel: no message for %g s: wheels stopped (cmd_vel_timeout of its <drive>; "
                             "logged once)", name, self.sim.entities.drive(name).cmd_vel_timeout)

    # ------------------------------------------------------------------ outgoing
    def on_step(self, sim: Simulation) -> None:
        """Publish /clock (every ``clock_every`` steps) and the robot states (every ``state_every`` steps)."""
        n = sim.step_count
        if n % self.state_every == 0:
            if self.clock_step != n:  # a stamped state message never runs ahead of /clock
                self.publish_clock()
            self.publish_state(entities=False)
        elif n % self.clock_every == 0 and (self.clock_gap <= 0 or time.monotonic() >= self._next_clock):
            self.publish_clock()
        if self.entity_every and n % self.entity_every == 0:
            if self.clock_behind:  # the /clock policy: never ahead of /clock
                self.publish_clock()
            self.publish_entities()
        if self._cmd_vel_deadline:
            self._stop_stale_cmd_vel(n)
        self.people.on_step(n)

    def publish_clock(self) -> None:
        """Publish the current time now (at start, after a reset, when the simulation goes idle, and by the /clock
        policy of :meth:`on_step`)."""
        n = self.sim.step_count
        self._send(self.clock_pub, self._clock.pack(*divmod(n * self.dt_ns, 1_000_000_000)))
        self.clock_step = n
        if self.clock_gap > 0:
            self._next_clock = time.monotonic() + self.clock_gap

    @property
    def clock_behind(self) -> bool:
        """Whether the last step's time is not on /clock yet (the wall-time limit skipped it)."""
        return self.clock_step != self.sim.step_count

    def publish_state(self, entities: bool = True) -> None:
        """odom and joint_states of every robot, and their transforms on /tf (odom -> base_link, every movable
        joint, free roots; each person's feet and links) in one message, stamped with the current step.

        The messages are serialized templates (:class:`CdrTemplate`) in which only the stamp, the pose, the
        velocities and the joint values are rewritten; the joint transforms are computed by the core
        (:meth:`sigcore.sim.frames.Frames.transforms`) from the positions published in joint_states.

        Args:
            entities: Also the entity transforms (:meth:`publish_entities`; at start and after a reset, while
                :meth:`on_step` publishes them at their own rate).
        """
        sim = self.sim
        sec, nanosec = divmod(sim.step_count * self.dt_ns, 1_000_000_000)
        poses: list[float] = []
        for odo, pub, template, tf in self._odom:
            s = odo.state
            qz, qw = math.sin(s.yaw / 2), math.cos(s.yaw / 2)
            self._send(pub, template.pack(sec, nanosec, s.x, s.y, qz, qw, s.v, s.w))
            if tf:
                poses += (sec, nanosec, s.x, s.y, 0.0, 0.0, 0.0, qz, qw)
        backend, transforms = sim.backend, sim.frames.transforms
        for name, joints, pub, template, moving in self._joint_states:
            positions = [backend.get_joint_angle(name, j) for j in joints]
            self._send(pub, template.pack(sec, nanosec, *positions,
                                          *[backend.get_joint_velocity(name, j) for j in joints]))
            if moving:
                for _, _, (x, y, z), (w, qx, qy, qz) in transforms(name, positions):
                    poses += (sec, nanosec, x, y, z, qx, qy, qz, w)
        for name in self._people:  # each person's feet and links (REP-155 frames), at the backend's joint angles
            for _, _, (x, y, z), (w, qx, qy, qz) in transforms(name):
                poses += (sec, nanosec, x, y, z, qx, qy, qz, w)
        if self._tf is not None:
            self._send(self.tf_pub, self._tf.pack(*poses))
        if entities and self._entity_tf is not None:
            self.publish_entities()

    def publish_entities(self) -> None:
        """``world -> <entity>`` of every object and human on /tf, stamped with the current step (if
        ``entity_tf_rate`` is not 0)."""
        if self._entity_tf is None:
            return
        sec, nanosec = divmod(self.sim.step_count * self.dt_ns, 1_000_000_000)
        values: list[float] = []
        for _, _, (x, y, z), (w, qx, qy, qz) in self.sim.frames.entity_transforms():
            values += (sec, nanosec, x, y, z, qx, qy, qz, w)
        self._send(self.tf_pub, self._entity_tf.pack(*values))

    def _scan(self, scan: Scan) -> None:
        pub = self.scan_pub.get((scan.robot, scan.lidar))
        if pub is not None:
            if self.clock_behind:  # the /clock policy: a scan never runs ahead of /clock
                self.publish_clock()
            stamp = round(scan.stamp / self.sim.dt) * self.dt_ns
            msg = fill_message(LaserScan(), scan.fields(self.sim.frames.name(scan.robot, scan.frame), stamp))
            if self.sim.publications.raw_wanted:  # a recorder takes the serialized message
                self._send(pub, serialize_message(msg), stamp)
            else:
                pub.publish(msg)

    def _send(self, pub: Any, data: bytes, stamp_ns: int | None = None) -> None:
        """Publish serialized ``data`` on ``pub`` and hand it to the recorders, if any (the publication contract's
        :meth:`~sigcore.publish.Publications.raw`), stamped ``stamp_ns`` (default: the current step)."""
        pub.publish(data)
        publications = self.sim.publications
        if publications.raw_wanted:
            publications.raw(*offered(pub), self.sim.stamp_ns() if stamp_ns is None else stamp_ns, data)


def _odometry(frame: str, child: str, pose: tuple[float, ...], twist: tuple[float, ...]) -> CdrTemplate:
    """Odometry ``frame -> child`` with the pose and twist covariance diagonals ``pose`` and ``twist`` (fixed),
    filled with: stamp (sec, nanosec), position x, y [m], orientation z, w, linear x [m/s], angular z [rad/s]
    (every other number 0)."""
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = frame, child
    for i in range(6):
        msg.pose.covariance[7 * i], msg.twist.covariance[7 * i] = pose[i], twist[i]
    return CdrTemplate(msg, ["header.stamp.sec", "header.stamp.nanosec", "pose.pose.position.x",
                             "pose.pose.position.y", "pose.pose.orientation.z", "pose.pose.orientation.w",
                             "twist.twist.linear.x", "twist.twist.angular.z"])


def _transforms(frames: list[tuple[str, str]]) -> CdrTemplate:
    """TFMessage of transforms ``parent -> child``, each filled with: stamp (sec, nanosec), translation x, y, z [m],
    rotation x, y, z, w."""
    msg = TFMessage(transforms=[TransformStamped() for _ in frames])
    fields = []
    for i, (tf, (parent, child)) in enumerate(zip(msg.transforms, frames, strict=True)):
        tf.header.frame_id, tf.child_frame_id = parent, child
        fields += [f"transforms.{i}.{name}" for name in ("header.stamp.sec", "header.stamp.nanosec",
                                                          "transform.translation.x", "transform.translation.y",
                                                          "transform.translation.z", "transform.rotation.x",
                                                          "transform.rotation.y", "transform.rotation.z",
                                                          "transform.rotation.w")]
    return CdrTemplate(msg, fields)


def _joint_state(joints: list[str]) -> CdrTemplate:
    """JointState of ``joints`` filled with: stamp (sec, nanosec), every position, every velocity."""
    msg = JointState()
    msg.name = list(joints)
    msg.position, msg.velocity = [0.0] * len(joints), [0.0] * len(joints)
    return CdrTemplate(msg, ["header.stamp.sec", "header.stamp.nanosec", "position", "velocity"])
