"""Listen to /tf for a while (the simulation running): every (parent, child) pair with the stamps it came with."""

import sys

from common import Client, emit
from rclpy.qos import QoSProfile, ReliabilityPolicy
from tf2_msgs.msg import TFMessage

c = Client("tf_listen")
c.wait_ready()
tfs = c.listen(TFMessage, "/tf", QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
c.spin(float(sys.argv[1]))
pairs: dict[str, list[int]] = {}
for m in tfs:
    for t in m.transforms:
        key = f"{t.header.frame_id} {t.child_frame_id}"
        pairs.setdefault(key, []).append(t.header.stamp.sec * 1_000_000_000 + t.header.stamp.nanosec)
emit(pairs)
