"""QoS and rates as configured by the world's <plugin name="ros2">: publishers' QoS, /clock period, prefix."""

from common import Client, emit
from rclpy.qos import DurabilityPolicy, ReliabilityPolicy, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from simulation_interfaces.srv import GetSimulationState

c = Client("qos_probe")
c.wait_ready()
clocks = c.listen(Clock, "/clock", qos_profile_sensor_data)
c.wait_for(lambda: len(clocks) > 10, 10.0)
info = {topic: [ReliabilityPolicy(i.qos_profile.reliability).name, DurabilityPolicy(i.qos_profile.durability).name,
                i.qos_profile.depth]
        for topic in ("/clock", "/bot/scan") for i in c.node.get_publishers_info_by_topic(topic)}
state = c.call(GetSimulationState, "/sim/get_simulation_state", timeout=5.0)
emit({"qos": info, "clock": [m.clock.sec + m.clock.nanosec * 1e-9 for m in clocks],
      "prefixed_state": state.state.state if state is not None else None,
      "sigros": bool(c.node.get_service_names_and_types_by_node("sigcore", "/") and
                     any(n.startswith("/bot_") for n, _ in c.node.get_service_names_and_types()))})
