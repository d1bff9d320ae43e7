"""SLAM over ROS 2: ``map -> odom`` on /tf, ``/map`` (nav_msgs/OccupancyGrid) and ``/<robot>/slam_pose``.

Published when the world enables ``<plugin name="slam">``, from the feature's hand-off ``SlamFeature.latest``
(see docs/slam.md): after each processed scan, ``map -> odom`` and the pose stamped with the scan's time; the map at
most ``map_rate`` times per simulated second, when it changed, on a latched (transient-local) topic so late
subscribers get the last one. The tree is REP-105: ``world -> map -> odom -> base_link``.
"""

from __future__ import annotations

import math
from typing import Any

from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from tf2_msgs.msg import TFMessage

from sigcore.sim.simulation import Simulation

from .convert import stamp, transform
from .qos import Qos


class SlamTopics:
    """Publishes what the SLAM feature of ``sim`` produced, after each step in which it processed a scan."""

    def __init__(self, sim: Simulation, node: Node, qos: Qos, tf_pub: Any, prefix: str, map_rate: float = 1.0
                 ) -> None:
        self.feature: Any = sim.features["slam"]
        self.robot = self.feature.robot
        self.dt_ns = round(sim.dt * 1e9)
        self.tf_pub = tf_pub
        self.map_frame, self.odom_frame = prefix + "map", prefix + "odom"
        self.map_pub = node.create_publisher(OccupancyGrid, "/map", qos.latched("/map"))
        pose_topic = f"/{self.robot}/slam_pose"
        self.pose_pub = node.create_publisher(PoseStamped, pose_topic, qos.state(pose_topic))
        self.topics = {"/map": "nav_msgs/msg/OccupancyGrid", pose_topic: "geometry_msgs/msg/PoseStamped"}
        self.map_period = 1.0 / map_rate
        self._last_stamp = -1.0
        self._last_map_time = -math.inf
        self._last_updates = -1

    def on_step(self, sim: Simulation) -> None:
        """Publish a new SLAM result, if the feature produced one in this step."""
        state = self.feature.latest
        if state is None or state.stamp == self._last_stamp:
            return
        self._last_stamp = state.stamp
        t = stamp(round(state.stamp / sim.dt), self.dt_ns)
        m2o = state.map_to_odom
        tf = transform(self.map_frame, self.odom_frame, t, (m2o.x, m2o.y, 0.0),
                        (math.cos(m2o.yaw / 2), 0.0, 0.0, math.sin(m2o.yaw / 2)))
        self.tf_pub.publish(TFMessage(transforms=[tf]))
        pose = PoseStamped()
        pose.header.stamp, pose.header.frame_id = t, self.map_frame
        p = state.map_to_base
        pose.pose.position.x, pose.pose.position.y = p.x, p.y
        pose.pose.orientation.w, pose.pose.orientation.z = math.cos(p.yaw / 2), math.sin(p.yaw / 2)
        self.pose_pub.publish(pose)
        grid = state.grid
        if grid.updates != self._last_updates and state.stamp - self._last_map_time >= self.map_period - 1e-9:
            self._last_updates, self._last_map_time = grid.updates, state.stamp
            self.map_pub.publish(self.occupancy_grid(grid, t))

    def occupancy_grid(self, grid: Any, t: Any) -> OccupancyGrid:
        """``nav_msgs/OccupancyGrid`` of the feature's grid (row-major from the origin cell, -1 unknown)."""
        msg = OccupancyGrid()
        msg.header.stamp, msg.header.frame_id = t, self.map_frame
        msg.info.map_load_time = t
        msg.info.resolution = float(grid.resolution)
        msg.info.width, msg.info.height = int(grid.width), int(grid.height)
        msg.info.origin.position.x, msg.info.origin.position.y = grid.origin
        msg.info.origin.orientation.w = 1.0
        msg.data = grid.data().ravel().tobytes()
        return msg
