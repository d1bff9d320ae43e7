"""Walk the person 'man' with Twist messages on /man/cmd_vel (0.8 m/s, then a refused 2.5 m/s, then nothing: it
stands after the timeout), following its ground truth and its REP-155 frames on /tf."""

import time

from common import Client, emit
from geometry_msgs.msg import Twist
from simulation_interfaces.srv import GetEntityState, ResetSimulation
from tf2_msgs.msg import TFMessage

c = Client("walk_probe")
c.wait_ready()
c.call(ResetSimulation, "/reset_simulation")
tfs = c.listen(TFMessage, "/tf")
c.wait_for(lambda: bool(tfs), 10.0)


def truth():
    s = c.call(GetEntityState, "/get_entity_state", entity="man").state
    return [s.pose.position.x, s.pose.position.y]


def knee():
    """The latest transform of the left knee (l_hip_man -> l_knee_man): its rotation's y part."""
    found = [t for m in tfs[-20:] for t in m.transforms if t.child_frame_id == "l_knee_man"]
    return found[-1].transform.rotation.y if found else None


start = truth()
knees = []
end = time.monotonic() + 1.5
while time.monotonic() < end:
    c.publish(Twist, "/man/cmd_vel", **{"linear.x": 0.8, "angular.z": 0.0})
    c.spin(0.1)
    knees.append(knee())
walked = truth()
c.publish(Twist, "/man/cmd_vel", **{"linear.x": 2.5, "angular.z": 0.0})  # refused: too fast
c.spin(0.2)
after_refusal = truth()
c.spin(1.5)  # no message for longer than the 0.5 s timeout: it stands
stood = truth()
c.spin(0.5)
emit({"start": start, "walked": walked, "after_refusal": after_refusal, "stood": stood, "still": truth(),
      "knees": [k for k in knees if k is not None],
      "frames": sorted({t.child_frame_id for m in tfs[-50:] for t in m.transforms
                        if t.child_frame_id.endswith("_man") or t.child_frame_id == "man"})})
