"""The graph and the odometry of a simulation started with --ros-args: names, nodes, the state rate."""

import time

from common import Client, emit
from nav_msgs.msg import Odometry

c = Client("ros_args_probe")
c.wait_ready()
odom = c.listen(Odometry, "/bot/odom")
end = time.monotonic() + 20
topics: dict = {}
services: dict = {}
while time.monotonic() < end:
    c.spin(0.5)
    topics = dict(c.node.get_topic_names_and_types())
    services = dict(c.node.get_service_names_and_types())
    if len(odom) >= 6 and any(s.startswith("/ns1/bot_") for s in services):
        break
stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in odom]
nodes = [(ns.rstrip("/") + "/" + n) for n, ns in c.node.get_node_names_and_namespaces()]
emit({"topics": sorted(topics), "services": sorted(services), "nodes": nodes, "odom": stamps})
