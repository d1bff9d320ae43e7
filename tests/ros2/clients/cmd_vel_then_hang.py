"""A client that drives 'bot' with cmd_vel and then hangs, to be killed as if it crashed: 0.2 m/s at 10 Hz
(wall time) for 0.5 s, then one last message at 0.4 m/s (so its step shows in joint_states), then nothing."""

import sys
import time

from common import Client
from geometry_msgs.msg import Twist

c = Client("cmd_vel_crasher")
c.wait_ready()
for _ in range(5):
    c.publish(Twist, "/bot/cmd_vel", **{"linear.x": 0.2, "angular.z": 0.0})
    c.spin(0.1)
c.publish(Twist, "/bot/cmd_vel", **{"linear.x": 0.4, "angular.z": 0.0})
c.spin(0.05)
sys.stdout.write("sent\n")
sys.stdout.flush()
while True:  # hang until killed (no clean shutdown: as a crashed process)
    time.sleep(1.0)
