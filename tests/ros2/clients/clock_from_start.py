"""Subscribe to /clock (started late, after the simulation is up) and report the stamps of the first seconds."""

import sys

from common import Client, emit
from rosgraph_msgs.msg import Clock

topic = sys.argv[1] if len(sys.argv) > 1 else "/clock"
c = Client("late_clock_probe")
clocks = c.listen(Clock, topic)


def now() -> float:
    return clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9 if clocks else -1.0


c.wait_for(lambda: now() >= 1.0, 30.0)
stamps = [m.clock.sec + m.clock.nanosec * 1e-9 for m in clocks]
emit({"first": stamps[0] if stamps else None, "last": stamps[-1] if stamps else None, "count": len(stamps),
      "zeros": sum(1 for s in stamps if s == 0.0),
      "monotonic": all(b >= a for a, b in zip(stamps, stamps[1:], strict=False))})
