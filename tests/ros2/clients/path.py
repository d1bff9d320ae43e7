"""Walk the person 'man' along a nav_msgs/Path on /man/path (two poses, at 1.0 m/s), then send paths it must refuse
(through the wall, in another frame, with no poses, with a NaN): it stays where the first path took it."""

import math
import time

from common import Client, emit
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from simulation_interfaces.srv import GetEntityState, ResetSimulation

c = Client("path_probe")
c.wait_ready()
c.call(ResetSimulation, "/reset_simulation")


def truth():
    s = c.call(GetEntityState, "/get_entity_state", entity="man").state
    return [s.pose.position.x, s.pose.position.y]


def pose(x, y):
    p = PoseStamped()
    p.header.frame_id = "world"
    p.pose.position.x, p.pose.position.y = float(x), float(y)
    return p


start = truth()
c.publish(Path, "/man/path", **{"header.frame_id": "world", "poses": [pose(-1.5, -1.5), pose(-1.5, -1.0)]})
began = time.monotonic()
end = began + 15.0
while time.monotonic() < end and math.dist(truth(), [-1.5, -1.0]) > 0.01:
    c.spin(0.1)
arrived = truth()
took = time.monotonic() - began
for frame, poses in (("world", [pose(4.0, -1.0)]), ("odom", [pose(-2.0, -1.0)]), ("world", []),
                     ("world", [pose(float("nan"), 0.0)])):
    c.publish(Path, "/man/path", **{"header.frame_id": frame, "poses": poses})
    c.spin(0.3)
c.spin(1.0)
emit({"start": start, "arrived": arrived, "took": took, "after": truth()})
