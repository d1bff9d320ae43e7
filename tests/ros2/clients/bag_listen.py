"""Listen to what `sigcore bag play` publishes: /clock, /sigcore/ground_truth and the latched /tf_static; report
the order of arrival (kind, stamp [ns]) once `count` ground-truth messages arrived (argv[1]) or after 60 s."""

import sys

from common import Client, emit
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage

count = int(sys.argv[1])
c = Client("bag_listener")
arrivals: list = []


def ns(stamp) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


deep = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
c.node.create_subscription(Clock, "/clock", lambda m: arrivals.append(("clock", ns(m.clock))), deep)
c.node.create_subscription(TFMessage, "/sigcore/ground_truth",
                           lambda m: arrivals.append(("truth", ns(m.transforms[0].header.stamp))), deep)
static: list = []
c.node.create_subscription(TFMessage, "/tf_static",
                           lambda m: static.append(sorted(t.child_frame_id for t in m.transforms)),
                           QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
print("listening", flush=True)
c.wait_for(lambda: sum(1 for k, _ in arrivals if k == "truth") >= count, 60.0)
c.spin(0.3)
emit({"arrivals": arrivals, "static": static})
