"""Watch /sigcore/ready: print ``ready true`` once it is true, then wait (bounded) for false; emit every value."""

from common import Client, emit
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Bool

c = Client("ready_watch")
seen: list[bool] = []
qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
c.node.create_subscription(Bool, "/sigcore/ready", lambda m: seen.append(bool(m.data)), qos)
print("ready true" if c.wait_for(lambda: True in seen, 60.0) else "ready never true", flush=True)
c.wait_for(lambda: seen[-1] is False, 60.0)
emit({"seen": seen})
