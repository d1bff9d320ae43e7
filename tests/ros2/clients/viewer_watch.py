"""Watch what a person's actions in the web viewer do on ROS 2: the messages robot_000 receives and /clock.

Runs until killed; prints one JSON line every 0.1 s of wall time: the newest /clock [s], how many /clock messages
arrived, and every message received on /robot_000_onRecvMsg so far (sender, content).
"""

import json
import time

from common import Client
from rosgraph_msgs.msg import Clock
from sigcore_msgs import msg

c = Client("viewer_watch")
c.wait_ready()
clocks = c.listen(Clock, "/clock")
received = c.listen(msg.OnRecvMsg, "/robot_000_onRecvMsg")
while True:
    c.spin(0.1)
    last = clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9 if clocks else None
    print(json.dumps({"wall": time.monotonic(), "clock": last, "clocks": len(clocks),
                      "received": [{"sender": m.sender, "content": m.content} for m in received]}), flush=True)
