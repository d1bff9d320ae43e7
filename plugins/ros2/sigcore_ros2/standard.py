"""Idiomatic ROS 2 topics: /clock, /tf, /tf_static, and per robot cmd_vel, odom, joint_states, LaserScans.

Frames (REP-105): with one robot, ``odom`` and the URDF's root link (e.g. ``base_link``); with several, each
robot's frames are prefixed with ``<robot>/``. ``world -> odom`` (the robot's start pose) and every fixed joint
of the URDF are on /tf_static; ``odom -> base_link`` (wheel odometry) is on /tf.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Any

import numpy as np
from geometry_msgs.msg import TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState, LaserScan
from tf2_msgs.msg import TFMessage

from sigcore.agent.exceptions import ApiError
from sigcore.agent.robot import RobotObj
from sigcore.geometry import quat_conj, quat_mul, quat_rotate
from sigcore.sim.lidar import Scan

from .cdr import CdrTemplate
from .convert import ranges_array, stamp, transform
from .qos import Qos
from .slam_topics import SlamTopics

if TYPE_CHECKING:
    from builtin_interfaces.msg import Time
    from rclpy.node import Node

    from sigcore.sim.simulation import Simulation

    from .config import Ros2Config
    from .receiver import Receiver
    from .sigros import SigRosEndpoints

log = logging.getLogger("sigcore.ros2")




class StandardEndpoints:
    """/clock, /tf, /tf_static and the per-robot topics; published by a step observer.

    Args:
        sim: The simulation.
        node: The node that owns the endpoints.
        receiver: Where the cmd_vel subscriptions are registered.
        qos: QoS profiles.
        config: Rates.
        sigros: The sig_ros endpoints (``<robot>_scan`` gets the same LaserScans), or None.
    """

    def __init__(self, sim: Simulation, node: Node, receiver: Receiver, qos: Qos, config: Ros2Config,
                 sigros: SigRosEndpoints | None) -> None:
        self.sim = sim
        self.sigros = sigros
        self.dt_ns = round(sim.dt * 1e9)
        self.clock_every = 1 if config.clock_rate <= 0 else max(1, round(1.0 / (config.clock_rate * sim.dt)))
        self.state_every = max(1, round(1.0 / (config.state_rate * sim.dt)))
        self.clock_pub = node.create_publisher(Clock, "/clock", qos.clock())
        self._clock = CdrTemplate(Clock(), ["clock.sec", "clock.nanosec"])
        self.tf_pub = node.create_publisher(TFMessage, "/tf", qos.tf())
        self.tf_static_pub = node.create_publisher(TFMessage, "/tf_static", qos.latched("/tf_static"))
        self.topics: dict[str, str] = {"/clock": "rosgraph_msgs/msg/Clock", "/tf": "tf2_msgs/msg/TFMessage",
                                       "/tf_static": "tf2_msgs/msg/TFMessage"}
        robots = [h for h in sim.agents.values() if isinstance(h, RobotObj)]
        self.prefix = {r.name: (f"{r.name}/" if len(robots) > 1 else "") for r in robots}
        self.base = {r.name: self.prefix[r.name] + sim.urdf(r.name).root for r in robots}
        self.odom_pub: dict[str, Any] = {}
        self.joint_pub: dict[str, Any] = {}
        self.joints: dict[str, list[str]] = {}
        self.scan_pub: dict[tuple[str, str], Any] = {}
        for robot in robots:
            name = robot.name
            self.joints[name] = [j.name for j in sim.urdf(name).movable_joints]
            topic = f"/{name}/joint_states"
            self.joint_pub[name] = node.create_publisher(JointState, topic, qos.state(topic))
            self.topics[topic] = "sensor_msgs/msg/JointState"
            if sim.robot_model(name).drive is not None:
                sim.enable_odometry(name)
                topic = f"/{name}/odom"
                self.odom_pub[name] = node.create_publisher(Odometry, topic, qos.state(topic))
                self.topics[topic] = "nav_msgs/msg/Odometry"
                topic = f"/{name}/cmd_vel"
                sub = node.create_subscription(Twist, topic, lambda *_: None, qos.commands(topic))
                receiver.add_subscription(sub, self._cmd_vel(robot))
                self.topics[topic] = "geometry_msgs/msg/Twist"
        for lidar in sim.lidars:
            topic = f"/{lidar.robot}/{lidar.model.name}"
            self.scan_pub[(lidar.robot, lidar.model.name)] = node.create_publisher(LaserScan, topic,
                                                                                   qos.sensor(topic))
            self.topics[topic] = "sensor_msgs/msg/LaserScan"
        self._warned: set[str] = set()
        # the state messages, serialized once: each publication only rewrites their numbers
        moving = [name for name in sim.odometry if name in self.odom_pub]
        self._odom = [(sim.odometry[name], self.odom_pub[name], _odometry(self.prefix[name] + "odom", self.base[name]))
                      for name in moving]
        self._tf = _transforms([(self.prefix[name] + "odom", self.base[name]) for name in moving])
        self._joint_states = [(name, joints, self.joint_pub[name], _joint_state(joints))
                              for name, joints in self.joints.items()]
        sim.scan_observers.append(self._scan)
        self.slam: SlamTopics | None = None
        if "slam" in sim.features:
            robot = sim.features["slam"].robot  # type: ignore[attr-defined]
            self.slam = SlamTopics(sim, node, qos, self.tf_pub, self.prefix[robot])
            self.topics.update(self.slam.topics)

    # ------------------------------------------------------------------ frames
    def static_transforms(self) -> TFMessage:
        """world -> odom per robot with a drive (world -> map for the robot SLAM maps: map -> odom then comes from
        SLAM on /tf), and every fixed joint of each robot's URDF."""
        sim, t = self.sim, stamp(self.sim.step_count, self.dt_ns)
        out = []
        for name, odo in sim.odometry.items():
            x, y, yaw = odo.origin
            child = "map" if self.slam is not None and self.slam.robot == name else "odom"
            out.append(transform("world", self.prefix[name] + child, t, (x, y, 0.0),
                                  (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))))
        for name, prefix in self.prefix.items():
            for joint in sim.urdf(name).joints:
                if joint.movable:
                    continue
                try:
                    pp, pq = sim.backend.get_pose(name, self._part(name, joint.parent))
                    cp, cq = sim.backend.get_pose(name, self._part(name, joint.child))
                except Exception:  # a link the backend merged away
                    continue
                inv = quat_conj(pq)
                out.append(transform(prefix + joint.parent, prefix + joint.child, t,
                                      quat_rotate(inv, np.asarray(cp) - np.asarray(pp)), quat_mul(inv, cq)))
        return TFMessage(transforms=out)

    def _part(self, robot: str, link: str) -> str | None:
        return None if link == self.sim.urdf(robot).root else link

    # ------------------------------------------------------------------ incoming
    def _cmd_vel(self, robot: RobotObj) -> Any:
        topic = f"/{robot.name}/cmd_vel"

        def handle(msg: Twist) -> None:
            try:
                robot.set_base_velocity(msg.linear.x, msg.angular.z)
            except ApiError as e:
                key = f"{topic}:{type(e).__name__}:{str(e)[:30]}"
                if key not in self._warned:
                    self._warned.add(key)
                    log.warning("%s refused (logged once): %s", topic, e)

        return handle

    # ------------------------------------------------------------------ outgoing
    def on_step(self, sim: Simulation) -> None:
        """Publish /clock (every ``clock_every`` steps) and the robot states (every ``state_every`` steps)."""
        n = sim.step_count
        if n % self.clock_every == 0:
            self.clock_pub.publish(self._clock.pack(*divmod(n * self.dt_ns, 1_000_000_000)))
        if n % self.state_every == 0:
            self.publish_state()
        if self.slam is not None:
            self.slam.on_step(sim)

    def publish_clock(self) -> None:
        """Publish the current time now (e.g. at start and after a reset)."""
        self.clock_pub.publish(self._clock.pack(*divmod(self.sim.step_count * self.dt_ns, 1_000_000_000)))

    def publish_state(self) -> None:
        """odom -> base_link on /tf, odom and joint_states of every robot, stamped with the current step.

        The messages are serialized templates (:class:`CdrTemplate`) in which only the stamp, the pose, the
        velocities and the joint values are rewritten.
        """
        sim = self.sim
        sec, nanosec = divmod(sim.step_count * self.dt_ns, 1_000_000_000)
        poses: list[float] = []
        for odo, pub, template in self._odom:
            s = odo.state
            qz, qw = math.sin(s.yaw / 2), math.cos(s.yaw / 2)
            pub.publish(template.pack(sec, nanosec, s.x, s.y, qz, qw, s.v, s.w))
            poses += (sec, nanosec, s.x, s.y, qz, qw)
        if poses:
            self.tf_pub.publish(self._tf.pack(*poses))
        backend = sim.backend
        for name, joints, pub, template in self._joint_states:
            pub.publish(template.pack(sec, nanosec, *[backend.get_joint_angle(name, j) for j in joints],
                                      *[backend.get_joint_velocity(name, j) for j in joints]))

    @staticmethod
    def scan_publisher(sim: Simulation, sigros: SigRosEndpoints) -> Any:
        """A scan observer feeding only ``<robot>_scan`` (when the standard topics are switched off)."""
        dt_ns = round(sim.dt * 1e9)

        def observe(scan: Scan) -> None:
            sigros.publish_scan(scan, laser_scan(scan, stamp(round(scan.stamp / sim.dt), dt_ns), scan.frame))

        sim.scan_observers.append(observe)
        return observe

    def _scan(self, scan: Scan) -> None:
        msg = laser_scan(scan, stamp(round(scan.stamp / self.sim.dt), self.dt_ns),
                         self.prefix.get(scan.robot, "") + scan.frame)
        pub = self.scan_pub.get((scan.robot, scan.lidar))
        if pub is not None:
            pub.publish(msg)
        if self.sigros is not None:
            self.sigros.publish_scan(scan, msg)


def _odometry(frame: str, child: str) -> CdrTemplate:
    """Odometry ``frame -> child`` filled with: stamp (sec, nanosec), position x, y [m], orientation z, w,
    linear x [m/s], angular z [rad/s] (every other number 0)."""
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = frame, child
    return CdrTemplate(msg, ["header.stamp.sec", "header.stamp.nanosec", "pose.pose.position.x",
                             "pose.pose.position.y", "pose.pose.orientation.z", "pose.pose.orientation.w",
                             "twist.twist.linear.x", "twist.twist.angular.z"])


def _transforms(frames: list[tuple[str, str]]) -> CdrTemplate:
    """TFMessage of planar transforms ``parent -> child``, each filled with: stamp (sec, nanosec), translation
    x, y [m], rotation z, w (every other number 0)."""
    msg = TFMessage(transforms=[TransformStamped() for _ in frames])
    fields = []
    for i, (tf, (parent, child)) in enumerate(zip(msg.transforms, frames, strict=True)):
        tf.header.frame_id, tf.child_frame_id = parent, child
        fields += [f"transforms.{i}.{name}" for name in ("header.stamp.sec", "header.stamp.nanosec",
                                                          "transform.translation.x", "transform.translation.y",
                                                          "transform.rotation.z", "transform.rotation.w")]
    return CdrTemplate(msg, fields)


def _joint_state(joints: list[str]) -> CdrTemplate:
    """JointState of ``joints`` filled with: stamp (sec, nanosec), every position, every velocity."""
    msg = JointState()
    msg.name = list(joints)
    msg.position, msg.velocity = [0.0] * len(joints), [0.0] * len(joints)
    return CdrTemplate(msg, ["header.stamp.sec", "header.stamp.nanosec", "position", "velocity"])


def laser_scan(scan: Scan, t: Time, frame: str) -> LaserScan:
    """A LaserScan of ``scan`` stamped ``t`` in ``frame``."""
    msg = LaserScan()
    msg.header.stamp, msg.header.frame_id = t, frame
    msg.angle_min, msg.angle_max, msg.angle_increment = scan.angle_min, scan.angle_max, scan.angle_increment
    msg.time_increment = 0.0
    msg.scan_time, msg.range_min, msg.range_max = scan.scan_time, scan.range_min, scan.range_max
    msg.ranges = ranges_array(scan.ranges)
    return msg
