"""The ROS graph as seen from another process: topics, services (with types) and the action names."""

import time

from common import Client, emit

c = Client("graph_probe")
c.wait_ready()
expected = int(__import__("sys").argv[1])
end = time.monotonic() + 20
topics, services = {}, {}
while time.monotonic() < end:  # discovery of hundreds of endpoints takes a moment
    c.spin(0.5)
    topics = dict(c.node.get_topic_names_and_types())
    services = dict(c.node.get_service_names_and_types())
    if len(topics) + len(services) >= expected:
        break
emit({"topics": topics, "services": services})
