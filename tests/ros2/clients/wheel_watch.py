"""Record the left wheel speed of 'bot' from /bot/joint_states (stamped with simulated time) for argv[1] seconds
of wall time; emit [[stamp [s], velocity [rad/s]], ...]."""

import sys

from common import Client, emit
from sensor_msgs.msg import JointState

c = Client("wheel_watch")
c.wait_ready()
states = c.listen(JointState, "/bot/joint_states")
c.wait_for(lambda: bool(states), 10.0)
print("listening", flush=True)
c.spin(float(sys.argv[1]))
i = list(states[0].name).index("wheel_l_joint")
emit({"samples": [[s.header.stamp.sec + s.header.stamp.nanosec * 1e-9, s.velocity[i]] for s in states]})
