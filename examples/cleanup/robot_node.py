#!/usr/bin/env python3
"""The clean-up robot as a ROS 2 user writes it: plain rclpy, no sigcore import (successor of sig_ros's RobotCommand).

It asks the simulator where things are (``robot_000_get_obj_position``, ``robot_000_get_rotation``), drives with
``/robot_000/cmd_vel``, moves the arms joint by joint with ``robot_000_setJointTarget``, grasps with
``robot_000_grasp_obj`` once the hand is close, drives to the right trash box and releases with
``robot_000_releaseObj``. Time is the simulation's (``/clock``): the node works whatever the simulator's pace.

Run (with the simulator running ``--transport ros2``):  python examples/cleanup/robot_node.py
"""

from __future__ import annotations

import math
import sys

import rclpy
from geometry_msgs.msg import Twist
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sigcore_msgs.msg import ReleaseObj, SetJointAngle
from sigcore_msgs.srv import GetObjPosition, GetPartsPosition, GetRotation, GraspObj

ROBOT = "robot_000"
PERIOD = 0.02  # control period [s] of simulated time
# (item, trash box, arm): like the seeds' RobotCommand, the node knows which box takes which trash.
JOBS = [("can_0", "trashbox_2", "l"), ("apple_2", "trashbox_1", "l"), ("petbottle_1", "trashbox_0", "r")]

# sigbot's arm (worlds/models/sigbot/README.md): shoulders at (0, ±0.20, 1.15) in base_link, links 0.37 / 0.31 m,
# grasp point 0.15 m below the wrist pitch axis when the hand points down.
SHOULDER_Y, SHOULDER_Z, UPPER, FORE, HAND = 0.20, 1.15, 0.37, 0.31, 0.15
JOINTS = ("shoulder_pan_joint", "shoulder_pitch_joint", "elbow_joint", "wrist_pitch_joint", "wrist_roll_joint")
TUCK = (0.0, 0.4, 2.4, -2.1, 0.0)  # carry pose, hand above table height
WRIST_LIMIT = 2.2  # the wrist pitch joints' limits in sigbot.urdf [rad]
HOVER, DROP_Z, GRASP_ABOVE, GRASP_RADIUS = 0.90, 0.65, 0.03, 0.09
PICK_AHEAD, PICK_SIDE, DROP_AHEAD, DROP_SIDE, STAGE = 0.50, 0.20, 0.52, 0.10, 0.80


def wrap(a: float) -> float:
    """Angle in (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


def hand_down(side: str, x: float, y: float, z: float) -> tuple[float, ...]:
    """Arm joint angles putting the grasp point at (x, y, z) in base_link, hand pointing down."""
    sy = SHOULDER_Y if side == "l" else -SHOULDER_Y
    reach, drop = math.hypot(x, y - sy), z + HAND - SHOULDER_Z
    c = (reach * reach + drop * drop - UPPER**2 - FORE**2) / (2 * UPPER * FORE)
    elbow = math.acos(max(-1.0, min(1.0, c)))
    pitch = math.atan2(reach, -drop) - math.atan2(FORE * math.sin(elbow), UPPER + FORE * math.cos(elbow))
    wrist = max(-WRIST_LIMIT, min(WRIST_LIMIT, -(pitch + elbow)))  # a hair past the limit is refused otherwise
    return (math.atan2(y - sy, x), pitch, elbow, wrist, 0.0)


def stop_pose(tx: float, ty: float, ahead: float, side_offset: float, side: str) -> tuple[float, float, float,
                                                                                             float, float]:
    """Base pose (x, y, yaw, stage x, stage y) facing across the corridor with the target ahead and to one side."""
    yaw = math.pi / 2 if ty > 0 else -math.pi / 2
    fx, fy = math.cos(yaw), math.sin(yaw)
    s = side_offset if side == "l" else -side_offset
    x, y = tx - ahead * fx + s * fy, ty - ahead * fy - s * fx
    return x, y, yaw, x - STAGE * fx, y - STAGE * fy


class CleanupRobot(Node):
    """Cleans up every trash item of JOBS, then stops."""

    def __init__(self) -> None:
        super().__init__("cleanup_robot")
        self.sim_time = -1.0
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.create_subscription(Clock, "/clock", self._on_clock, qos)
        self.cmd_vel = self.create_publisher(Twist, f"/{ROBOT}/cmd_vel", 10)
        self.joint_target = self.create_publisher(SetJointAngle, f"{ROBOT}_setJointTarget", 50)
        self.release = self.create_publisher(ReleaseObj, f"{ROBOT}_releaseObj", 10)
        self.position = self.create_client(GetObjPosition, f"{ROBOT}_get_obj_position")
        self.rotation = self.create_client(GetRotation, f"{ROBOT}_get_rotation")
        self.parts = self.create_client(GetPartsPosition, f"{ROBOT}_get_parts_position")
        self.grasp = self.create_client(GraspObj, f"{ROBOT}_grasp_obj")
        self.v = self.w = 0.0
        self.arm = {"l": [0.0] * 5, "r": [0.0] * 5}

    # ------------------------------------------------------------------ ROS plumbing
    def _on_clock(self, msg: Clock) -> None:
        self.sim_time = msg.clock.sec + msg.clock.nanosec * 1e-9

    def call(self, client, request):  # type: ignore[no-untyped-def]
        if not client.wait_for_service(timeout_sec=30.0):
            raise RuntimeError(f"service {client.srv_name} is not available")
        future = client.call_async(request)
        rclpy.spin_until_future_complete(self, future, timeout_sec=10.0)
        if not future.done():
            raise RuntimeError(f"{client.srv_name} did not answer")
        return future.result()

    def tick(self) -> None:
        """Wait until the next control period of simulated time."""
        target = self.sim_time + PERIOD
        while rclpy.ok() and self.sim_time < target:
            rclpy.spin_once(self, timeout_sec=0.05)

    def where(self, name: str) -> tuple[float, float, float]:
        r = self.call(self.position, GetObjPosition.Request(name=name))
        if not r.success:
            raise RuntimeError(r.message)
        return r.pos_x, r.pos_y, r.pos_z

    def pose(self) -> tuple[float, float, float]:
        x, y, _ = self.where("")
        q = self.call(self.rotation, GetRotation.Request(name=""))
        return x, y, math.atan2(2 * (q.qw * q.qz + q.qx * q.qy), 1 - 2 * (q.qy**2 + q.qz**2))

    def in_base(self, p: tuple[float, float, float]) -> tuple[float, float, float]:
        x, y, yaw = self.pose()
        dx, dy = p[0] - x, p[1] - y
        return math.cos(yaw) * dx + math.sin(yaw) * dy, -math.sin(yaw) * dx + math.cos(yaw) * dy, p[2]

    # ------------------------------------------------------------------ base
    def command(self, v: float, w: float) -> None:
        self.v += max(-PERIOD, min(PERIOD, v - self.v))  # 1 m/s^2
        self.w += max(-3 * PERIOD, min(3 * PERIOD, w - self.w))  # 3 rad/s^2
        msg = Twist()
        msg.linear.x, msg.angular.z = self.v, self.w
        self.cmd_vel.publish(msg)

    def halt(self) -> None:
        while abs(self.v) > 1e-9 or abs(self.w) > 1e-9:
            self.command(0.0, 0.0)
            self.tick()

    def turn_to(self, yaw: float) -> None:
        while True:
            err = wrap(yaw - self.pose()[2])
            if abs(err) < 0.01:
                return self.halt()
            self.command(0.0, math.copysign(min(1.5, 0.8 * math.sqrt(6 * abs(err)), 4 * abs(err)), err))
            self.tick()

    def go_to(self, x: float, y: float, backwards: bool = False) -> None:
        while True:
            px, py, yaw = self.pose()
            dist = math.hypot(x - px, y - py)
            if dist < 0.01:
                return self.halt()
            err = wrap(math.atan2(y - py, x - px) + (math.pi if backwards else 0.0) - yaw)
            if abs(err) > 0.3 and dist > 0.05:
                self.command(0.0, 0.0 if abs(self.v) > 0.02 else math.copysign(min(1.5, 4 * abs(err)), err))
            else:
                speed = min(0.8, 0.8 * math.sqrt(2 * max(dist * math.cos(err), 0.0)), 2 * dist)
                self.command(-speed if backwards else speed, max(-1.5, min(1.5, 3 * err)) if dist > 0.05 else 0.0)
            self.tick()

    def approach(self, stop: tuple[float, float, float, float, float]) -> None:
        x, y, yaw, sx, sy = stop
        self.go_to(sx, sy)
        self.turn_to(yaw)
        self.go_to(x, y)
        self.turn_to(yaw)

    # ------------------------------------------------------------------ arm
    def move_arm(self, side: str, target: tuple[float, ...], duration: float, until=None) -> bool:  # type: ignore[no-untyped-def]
        start, steps = list(self.arm[side]), max(1, round(duration / PERIOD))
        for k in range(1, steps + 1):
            s = k / steps
            s = s * s * (3 - 2 * s)
            for i, joint in enumerate(JOINTS):
                self.arm[side][i] = start[i] + s * (target[i] - start[i])
                self.joint_target.publish(SetJointAngle(name="", joint_name=f"{side}_{joint}",
                                                        angle=self.arm[side][i]))
            self.tick()
            if until is not None and until():
                return True
        for _ in range(25):  # let the servos settle
            self.tick()
        return False

    def hand_near(self, side: str, item: str) -> bool:
        h = self.call(self.parts, GetPartsPosition.Request(name="", part=f"{side}_hand_link"))
        return math.dist((h.pos_x, h.pos_y, h.pos_z), self.where(item)) < GRASP_RADIUS

    # ------------------------------------------------------------------ the task
    def clean(self, item: str, box: str, side: str) -> None:
        ix, iy, _ = self.where(item)
        pick = stop_pose(ix, iy, PICK_AHEAD, PICK_SIDE, side)
        self.get_logger().info(f"going to pick {item} with the {side} arm")
        self.approach(pick)
        x, y, z = self.in_base(self.where(item))
        self.move_arm(side, hand_down(side, x, y, HOVER), 1.2)
        self.move_arm(side, hand_down(side, x, y, z + GRASP_ABOVE), 1.0, until=lambda: self.hand_near(side, item))
        r = self.call(self.grasp, GraspObj.Request(part=f"{side}_hand_link", obj=item))
        self.get_logger().info(f"grasp {item}: ok={r.ok} {r.message}")
        self.move_arm(side, TUCK, 1.2)
        self.go_to(pick[3], pick[4], backwards=True)
        if not r.ok:
            return
        bx, by, _ = self.where(box)
        drop = stop_pose(bx, by, DROP_AHEAD, DROP_SIDE, side)
        self.approach(drop)
        x, y, _ = self.in_base(self.where(box))
        self.move_arm(side, hand_down(side, x, y, DROP_Z), 1.2)
        self.release.publish(ReleaseObj(arm=f"{side}_hand_link"))
        self.get_logger().info(f"released {item} over {box}")
        for _ in range(15):
            self.tick()
        self.move_arm(side, TUCK, 1.0)
        self.go_to(drop[3], drop[4], backwards=True)

    def run(self) -> None:
        while rclpy.ok() and self.sim_time < 0:
            rclpy.spin_once(self, timeout_sec=0.1)  # wait for the simulator's /clock
        self.move_arm("l", TUCK, 1.0)
        self.move_arm("r", TUCK, 0.2)
        for item, box, side in JOBS:
            self.clean(item, box, side)
        self.halt()
        self.get_logger().info("done")


def main() -> int:
    rclpy.init()
    node = CleanupRobot()
    try:
        node.run()
        return 0
    except KeyboardInterrupt:
        return 0  # the simulator ended the task
    except RuntimeError as e:
        node.get_logger().error(str(e))
        return 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
