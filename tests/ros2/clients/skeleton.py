"""Pose the person 'man' with a JointState stream on /man/skeleton (REP-155 joints and the root's pose, at about
30 Hz for 1 s), then send skeletons it must refuse (lengths that differ, an unknown joint, a NaN, a joint named
twice); report the transforms of its frames on /tf and /tf_static, as they were after the stream and at the end."""

import math
import time

from common import Client, emit
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from simulation_interfaces.srv import ResetSimulation
from tf2_msgs.msg import TFMessage

POSE = {"l_y_shoulder": 0.3, "l_p_shoulder": 1.1, "l_r_shoulder": -0.4, "l_elbow": 0.9, "waist": 0.2,
        "y_head": -0.5}
ROOT = {"root_x": -1.0, "root_y": -1.0, "root_yaw": 0.7}

c = Client("skeleton_probe")
c.wait_ready()
c.call(ResetSimulation, "/reset_simulation")
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
static = c.listen(TFMessage, "/tf_static", latched)
tfs = c.listen(TFMessage, "/tf")


def frames():
    """The latest transform of each of the person's frames: child -> [parent, translation, rotation (w, x, y, z)]."""
    out = {}
    for m in [*static, *tfs]:
        for t in m.transforms:
            if t.child_frame_id == "man" or t.child_frame_id.endswith("_man"):
                v, q = t.transform.translation, t.transform.rotation
                out[t.child_frame_id] = [t.header.frame_id, [v.x, v.y, v.z], [q.w, q.x, q.y, q.z]]
    return out


end = time.monotonic() + 1.0
while time.monotonic() < end:
    c.publish(JointState, "/man/skeleton", name=[*POSE, *ROOT], position=[*POSE.values(), *ROOT.values()])
    c.spin(0.033)
c.spin(0.5)
posed = frames()
for names, positions in ((["l_elbow", "r_elbow"], [0.1]), (["l_elbow", "l_wristt"], [0.1, 0.1]),
                         (["l_elbow"], [math.nan]), (["l_elbow", "l_elbow"], [0.1, 0.2])):
    c.publish(JointState, "/man/skeleton", name=names, position=positions)
    c.spin(0.2)
c.spin(0.5)
emit({"pose": POSE, "root": ROOT, "posed": posed, "after": frames()})
