"""The topics of the live graph once discovery has settled (the count stops changing for 3 s)."""

import time

from common import Client, emit

c = Client("topic_probe")
c.wait_ready()
end = time.monotonic() + 40
topics: dict = {}
stable_since = time.monotonic()
while time.monotonic() < end:
    c.spin(0.5)
    now = dict(c.node.get_topic_names_and_types())
    if len(now) != len(topics):
        topics, stable_since = now, time.monotonic()
    elif time.monotonic() - stable_since > 3.0:
        break
emit({"topics": {name: types for name, types in sorted(topics.items())}})
