"""The /clock policy: play a paused simulation for 2 s of simulated time, pause it, and report what was received.

Prints the /clock stamps and the stamps of odom, /tf and the scan (integer nanoseconds), the time of the step the
simulation paused at (the stamp of a get_entity_state answer), and how many steps were taken.
"""

from common import Client, emit
from nav_msgs.msg import Odometry
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import GetEntityState, SetSimulationState
from tf2_msgs.msg import TFMessage


def ns(stamp):
    return stamp.sec * 1_000_000_000 + stamp.nanosec


c = Client("clock_policy_probe")
c.wait_ready()
deep = QoSProfile(depth=5000, reliability=ReliabilityPolicy.RELIABLE)
clocks = c.listen(Clock, "/clock", deep)
odoms = c.listen(Odometry, "/bot/odom", deep)
tfs = c.listen(TFMessage, "/tf", deep)
scans = c.listen(LaserScan, "/bot/scan", deep)
c.wait_for(lambda: bool(clocks), 10.0)
c.spin(1.0)  # every subscription matched (the paused simulation repeats /clock every 0.1 s)
start = ns(clocks[-1].clock)
played = c.call(SetSimulationState, "/set_simulation_state", **{"state.state": SimulationState.STATE_PLAYING})
c.wait_for(lambda: ns(clocks[-1].clock) >= start + 2_000_000_000, 30.0)
paused = c.call(SetSimulationState, "/set_simulation_state", **{"state.state": SimulationState.STATE_PAUSED})
state = c.call(GetEntityState, "/get_entity_state", entity="cube")
c.spin(0.5)
end = ns(state.state.header.stamp)
emit({"play": played.result.result, "pause": paused.result.result, "start": start, "end": end,
      "clock": sorted({ns(m.clock) for m in clocks}), "clock_messages": len(clocks),
      "odom": [ns(m.header.stamp) for m in odoms],
      "tf": [ns(t.header.stamp) for m in tfs for t in m.transforms],
      "scan": [ns(m.header.stamp) for m in scans]})
