#!/usr/bin/env python3
"""The clean-up robot as a ROS 2 user writes it: plain rclpy, no sigcore import (successor of sig_ros's RobotCommand).

It asks the simulator where things are (``robot_000_get_obj_position``, ``robot_000_get_rotation``), drives with
``/robot_000/cmd_vel``, moves the arms joint by joint with ``robot_000_setJointTarget``, grasps with
``robot_000_grasp_obj`` once the hand is close, drives to the right trash box and releases with
``robot_000_releaseObj``. Time is the simulation's (``/clock``): the node works whatever the simulator's pace.

With ``--lockstep`` the node advances the simulation itself: it pauses it (simulation_interfaces'
``set_simulation_state``) as soon as it plays, then takes each control period with ``step_simulation``. Nothing
then depends on how fast this machine answers: the simulation waits for the node, as fast as both can go.

Run (with the simulator running ``--transport ros2``):  python examples/cleanup/robot_node.py [--lockstep]
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sigcore_msgs.msg import ReleaseObj, SetJointAngle
from sigcore_msgs.srv import GetObjPosition, GetPartsPosition, GetRotation, GraspObj
from simulation_interfaces.msg import Result, SimulationState
from simulation_interfaces.srv import GetEntityState, SetSimulationState, StepSimulation
from std_msgs.msg import Bool

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
STALL = 5.0  # give up a motion that has made no progress for this long [s of simulated time]


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


class SimulationEnded(Exception):
    """The simulator has stopped (it says so on /sigcore/ready): the task is over, nothing is left to do."""


class CleanupRobot(Node):
    """Cleans up every trash item of JOBS that is in the world, then stops."""

    def __init__(self, lockstep: bool = False) -> None:
        super().__init__("cleanup_robot")
        self.sim_time = -1.0
        self.lockstep = lockstep
        self.timestep = 0.0  # the simulation's step [s], measured when --lockstep pauses it
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.clock = self.create_subscription(Clock, "/clock", self._on_clock, qos)
        self.sim_ready = True
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.create_subscription(Bool, "/sigcore/ready", lambda msg: setattr(self, "sim_ready", msg.data), latched)
        self.cmd_vel = self.create_publisher(Twist, f"/{ROBOT}/cmd_vel", 10)
        self.joint_target = self.create_publisher(SetJointAngle, f"{ROBOT}_setJointTarget", 50)
        self.release = self.create_publisher(ReleaseObj, f"{ROBOT}_releaseObj", 10)
        self.position = self.create_client(GetObjPosition, f"{ROBOT}_get_obj_position")
        self.rotation = self.create_client(GetRotation, f"{ROBOT}_get_rotation")
        self.parts = self.create_client(GetPartsPosition, f"{ROBOT}_get_parts_position")
        self.grasp = self.create_client(GraspObj, f"{ROBOT}_grasp_obj")
        self.set_state = self.create_client(SetSimulationState, "/set_simulation_state")
        self.step = self.create_client(StepSimulation, "/step_simulation")
        self.entity_state = self.create_client(GetEntityState, "/get_entity_state")
        self.v = self.w = 0.0
        self.arm = {"l": [0.0] * 5, "r": [0.0] * 5}
        # one executor for the node's whole life, spun a callback at a time: rclpy.spin_until_future_complete (the
        # global executor) took about 40 ms of busy CPU per service call in this node, against about 1.5 ms
        self.spinner = SingleThreadedExecutor()
        self.spinner.add_node(self)

    # ------------------------------------------------------------------ ROS plumbing
    def _on_clock(self, msg: Clock) -> None:
        if not self.timestep:  # --lockstep counts the time itself once it steps
            self.sim_time = msg.clock.sec + msg.clock.nanosec * 1e-9

    def call(self, client, request):  # type: ignore[no-untyped-def]
        if not client.wait_for_service(timeout_sec=30.0):
            raise RuntimeError(f"service {client.srv_name} is not available")
        future = client.call_async(request)
        deadline = time.monotonic() + 10.0
        while not future.done():
            if time.monotonic() > deadline or not rclpy.ok():
                raise RuntimeError(f"{client.srv_name} did not answer")
            self.spinner.spin_once(timeout_sec=0.1)
        return future.result()

    def tick(self) -> None:
        """Wait until the next control period of simulated time (--lockstep: take its steps)."""
        target = self.sim_time + PERIOD
        if self.lockstep:
            steps = max(1, round(PERIOD / self.timestep))
            r = self.call(self.step, StepSimulation.Request(steps=steps))
            if r.result.result != Result.RESULT_OK:
                deadline = time.monotonic() + 2.0
                while self.sim_ready and time.monotonic() < deadline:  # the simulator says false as it stops
                    self.spinner.spin_once(timeout_sec=0.1)
                if not self.sim_ready:
                    raise SimulationEnded(r.result.error_message)
                raise RuntimeError(f"step_simulation: {r.result.error_message}")
            self.sim_time += steps * self.timestep  # /clock is best effort: count the time ourselves
            self.spinner.spin_once(timeout_sec=0.0)
            return
        while rclpy.ok() and self.sim_time < target:
            self.spinner.spin_once(timeout_sec=0.05)

    def take_over(self) -> None:
        """--lockstep: pause the simulation once it plays; measure its step (the stamps of two single steps)."""
        start = self.sim_time
        while rclpy.ok() and self.sim_time <= start:  # the simulator plays once every node is there
            self.spinner.spin_once(timeout_sec=0.05)
        paused = SetSimulationState.Request(state=SimulationState(state=SimulationState.STATE_PAUSED))
        r = self.call(self.set_state, paused)
        if r.result.result not in (Result.RESULT_OK, SetSimulationState.Response.ALREADY_IN_TARGET_STATE):
            raise RuntimeError(f"cannot pause the simulation: {r.result.error_message}")
        stamps = []
        for _ in range(2):
            self.call(self.step, StepSimulation.Request(steps=1))
            stamp = self.call(self.entity_state, GetEntityState.Request(entity=ROBOT)).state.header.stamp
            stamps.append(stamp.sec + stamp.nanosec * 1e-9)
        self.timestep, self.sim_time = stamps[1] - stamps[0], stamps[1]
        self.destroy_subscription(self.clock)  # the node counts the time itself from now on
        if not 0.0 < self.timestep <= PERIOD:
            raise RuntimeError(f"lockstep: a step of {self.timestep:g} s; valid: 0 < step <= {PERIOD} s")
        self.get_logger().info(f"lockstep: paused at t = {self.sim_time:.3f} s; each control period is "
                               f"{round(PERIOD / self.timestep)} steps of {self.timestep:g} s")

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

    def stalled(self, progress: dict[str, float], error: float, what: str) -> bool:
        """Whether ``error`` has not improved by 1 mm (or mrad) for STALL seconds: then say so, and give up."""
        if error < progress.get("best", math.inf) - 1e-3:
            progress.update(best=error, since=self.sim_time)
        elif self.sim_time - progress.setdefault("since", self.sim_time) > STALL:
            self.get_logger().warning(f"{what}: no progress for {STALL:g} s, {error:.3f} off; going on")
            return True
        return False

    def turn_to(self, yaw: float) -> None:
        progress: dict[str, float] = {}
        while True:
            err = wrap(yaw - self.pose()[2])
            if abs(err) < 0.01 or self.stalled(progress, abs(err), f"turning to {yaw:.2f} rad"):
                return self.halt()
            self.command(0.0, math.copysign(min(1.5, 0.8 * math.sqrt(6 * abs(err)), 4 * abs(err)), err))
            self.tick()

    def go_to(self, x: float, y: float, backwards: bool = False) -> None:
        """Drive to (x, y): within 1 cm, or within 1 cm along the heading and 5 cm across it. Past the goal (a late
        stop), it backs up."""
        progress: dict[str, float] = {}
        while True:
            px, py, yaw = self.pose()
            dist = math.hypot(x - px, y - py)
            err = wrap(math.atan2(y - py, x - px) + (math.pi if backwards else 0.0) - yaw)
            along = dist * math.cos(err)  # < 0 once past the goal
            if dist < 0.01 or (dist < 0.05 and abs(along) < 0.01) or \
                    self.stalled(progress, dist, f"going to ({x:.2f}, {y:.2f})"):
                return self.halt()
            if abs(err) > 0.3 and dist > 0.05:
                self.command(0.0, 0.0 if abs(self.v) > 0.02 else math.copysign(min(1.5, 4 * abs(err)), err))
            else:
                speed = math.copysign(min(0.8, 0.8 * math.sqrt(2 * abs(along)), 2 * abs(along)), along)
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
            self.spinner.spin_once(timeout_sec=0.1)  # wait for the simulator's /clock
        if self.lockstep:
            self.take_over()
        self.move_arm("l", TUCK, 1.0)
        self.move_arm("r", TUCK, 0.2)
        for item, box, side in JOBS:
            if not self.call(self.position, GetObjPosition.Request(name=item)).success:
                self.get_logger().info(f"{item} is not in this world: nothing to clean up there")
                continue
            self.clean(item, box, side)
        self.halt()
        if self.lockstep:  # time must go on for the last item to come to rest in its box: give the clock back
            playing = SetSimulationState.Request(state=SimulationState(state=SimulationState.STATE_PLAYING))
            self.call(self.set_state, playing)
        self.get_logger().info("done")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lockstep", action="store_true",
                    help="pause the simulation and step it one control period at a time (step_simulation)")
    args, ros_args = ap.parse_known_args()
    rclpy.init(args=[sys.argv[0], *ros_args])
    node = CleanupRobot(args.lockstep)
    try:
        node.run()
        return 0
    except (KeyboardInterrupt, ExternalShutdownException):
        return 0  # the simulator ended the task
    except SimulationEnded as e:
        node.get_logger().info(f"the simulation ended ({e}): the task is over")
        return 0
    except RuntimeError as e:
        node.get_logger().error(str(e))
        return 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
