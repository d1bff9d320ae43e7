"""Drive 'bot' with cmd_vel and follow odom, /tf (odom -> base_link) and ground truth; also read
joint_states, the LaserScan, /tf_static and /clock."""

import time

from common import Client, emit, todict
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState, LaserScan
from simulation_interfaces.srv import GetEntityState, ResetSimulation
from tf2_msgs.msg import TFMessage

c = Client("drive_probe")
c.wait_ready()
c.call(ResetSimulation, "/reset_simulation")  # start from the world's poses, whatever earlier tests did
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
static = c.listen(TFMessage, "/tf_static", latched)
clocks = c.listen(Clock, "/clock")
odoms = c.listen(Odometry, "/bot/odom")
tfs = c.listen(TFMessage, "/tf")
joints = c.listen(JointState, "/bot/joint_states")
scans = c.listen(LaserScan, "/bot/scan", qos_profile_sensor_data)
sigros_scans = c.listen(LaserScan, "/bot_scan", qos_profile_sensor_data)
c.wait_for(lambda: odoms and scans and joints and static and sigros_scans, 10.0)


def truth():
    s = c.call(GetEntityState, "/get_entity_state", entity="bot").state
    return [s.pose.position.x, s.pose.position.y]


start_truth, start_odom = truth(), odoms[-1].pose.pose.position.x
end = time.monotonic() + 2.0
while time.monotonic() < end:
    c.publish(Twist, "/bot/cmd_vel", **{"linear.x": 0.4, "angular.z": 0.0})
    c.spin(0.1)
c.publish(Twist, "/bot/cmd_vel", **{"linear.x": 0.0, "angular.z": 0.0})
c.spin(0.5)
end_truth = truth()
n = len(odoms)
c.wait_for(lambda: len(odoms) > n + 2, 5.0)
odom = odoms[-1]


def stamp(h):
    return h.stamp.sec + h.stamp.nanosec * 1e-9


tf_odom = [t for m in tfs for t in m.transforms if t.header.frame_id == "odom"]
emit({
    "truth_dx": end_truth[0] - start_truth[0], "truth_dy": end_truth[1] - start_truth[1],
    "odom_dx": odom.pose.pose.position.x - start_odom, "odom_frames": [odom.header.frame_id, odom.child_frame_id],
    "odom_stamps": [stamp(o.header) for o in odoms[-20:]],
    "tf_last": todict(tf_odom[-1]) if tf_odom else None, "odom_last_x": odom.pose.pose.position.x,
    "tf_stamps": [stamp(t.header) for t in tf_odom[-20:]],
    "clock": [m.clock.sec + m.clock.nanosec * 1e-9 for m in clocks[-50:]],
    "joints": todict(joints[-1]), "scan": {k: v for k, v in todict(scans[-1]).items() if k != "ranges"},
    "scan_ranges": list(scans[-1].ranges)[:5], "scan_len": len(scans[-1].ranges),
    "scan_stamps": [stamp(s.header) for s in scans[-5:]], "sigros_scans": len(sigros_scans),
    "static": [[t.header.frame_id, t.child_frame_id] for m in static for t in m.transforms],
    "qos": {topic: [ReliabilityPolicy(i.qos_profile.reliability).name, DurabilityPolicy(i.qos_profile.durability).name]
            for topic in ("/clock", "/tf_static", "/bot/scan", "/tf", "/sigcore/ready")
            for i in c.node.get_publishers_info_by_topic(topic)},
})
