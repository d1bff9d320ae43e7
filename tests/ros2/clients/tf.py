"""The TF tree of a paused simulation (cleanup world): move joints, step in lockstep, and collect /tf_static, /tf,
/clock and the scans (with their writers' source timestamps), the odometry, and the backend's link positions.

Arguments: the robot, its URDF links (comma-separated), the joints to move as NAME=ANGLE (comma-separated), the steps
of one stride, the number of strides.
"""

import sys

from common import Client, emit, todict
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from sigcore_msgs import msg, srv
from simulation_interfaces.srv import StepSimulation
from tf2_msgs.msg import TFMessage

robot, links, moves, stride, strides = sys.argv[1], sys.argv[2].split(","), sys.argv[3], int(sys.argv[4]), \
    int(sys.argv[5])
c = Client("tf_probe")
c.wait_ready()
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
keep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
static = c.listen(TFMessage, "/tf_static", latched)
tfs = c.listen(TFMessage, "/tf", keep)
odoms = c.listen(Odometry, f"/{robot}/odom", keep)
clocks: list = []
scans: list = []
for msg_type, topic, into in ((Clock, "/clock", clocks), (LaserScan, f"/{robot}/base_scan", scans)):
    # with the writer's source timestamp (wall clock of the simulation process when it published)
    c.node.create_subscription(msg_type, topic, lambda m, info, into=into: into.append((m, info["source_timestamp"])),
                               keep)
c.wait_for(lambda: bool(static) and bool(clocks), 10.0)
c.spin(0.5)  # the other subscriptions match too


def ns(t):
    return t.sec * 1_000_000_000 + t.nanosec


def angle_of(joint):
    got = c.call(srv.GetJointAngle, f"/{robot}_get_joint_angle", name="", name_arm=joint)
    return None if got is None else got.angle


set_ok = True
for item in moves.split(","):
    joint, angle = item.split("=")
    for _ in range(3):  # a topic message is not acknowledged: check that it took effect, else send it again
        c.publish(msg.SetJointAngle, f"/{robot}_setJointAngle", name="", joint_name=joint, angle=float(angle))
        if c.wait_for(lambda joint=joint, angle=angle: abs((angle_of(joint) or 1e9) - float(angle)) < 1e-9, 3.0):
            break
    else:
        set_ok = False
steps = [c.call(StepSimulation, "/step_simulation", steps=stride).result.result for _ in range(strides)]
now = strides * stride
c.wait_for(lambda: any(ns(m.clock) > 0 for m, _ in clocks) and scans and odoms, 10.0)
c.spin(1.0)  # the last step's messages arrive
positions = {link: c.call(srv.GetPartsPosition, f"/{robot}_get_parts_position", name="", part=link)
             for link in links}
rotation = c.call(srv.GetRotation, f"/{robot}_get_rotation", name="")
entities = {name: c.call(srv.GetObjPosition, f"/{robot}_get_obj_position", name=name) for name in ("can_0", "man_0")}
emit({
    "set": set_ok,
    "steps": steps,
    "static": [todict(t) for m in static for t in m.transforms],
    "tf": [todict(t) for m in tfs for t in m.transforms],
    "clocks": [[ns(m.clock), ts] for m, ts in clocks],
    "scans": [[ns(m.header.stamp), ts, m.header.frame_id] for m, ts in scans],
    "odom": todict(odoms[-1]) if odoms else None,
    "positions": {k: [v.pos_x, v.pos_y, v.pos_z] for k, v in positions.items()},
    "rotation": [rotation.qw, rotation.qx, rotation.qy, rotation.qz],
    "entities": {k: [v.pos_x, v.pos_y, v.pos_z] for k, v in entities.items()},
})
