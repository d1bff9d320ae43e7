"""In lockstep (the simulation was started paused; every 0.1 s of simulated time is one step_simulation call):
drive 'bot' for 10 s (forward, back, turning, hard starts and stops), then steer it into the slanted wall by ground
truth and keep pushing; collect /bot_onCollisionMsg, noting which phase each message arrived in."""

import math

from common import Client, emit, todict
from sigcore_msgs import msg, srv
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import GetEntityState, StepSimulation

STEPS = 50  # steps per command: 0.1 s at the world's 2 ms
DRIVE = [((4.0, 4.0), 1.5), ((-4.0, -4.0), 1.5), ((-3.0, 3.0), 1.0), ((3.0, -3.0), 1.0), ((5.0, 2.0), 1.5),
         ((-5.0, -2.0), 1.5), ((0.0, 0.0), 0.5), ((6.0, 6.0), 0.5), ((-6.0, -6.0), 0.5), ((0.0, 0.0), 0.5)]
TARGET = (2.5, 0.0)  # on the wall's face (the line x + y = 2.5)

c = Client("contacts_probe")
c.wait_ready()
hits = c.listen(msg.OnCollisionMsg, "/bot_onCollisionMsg")
c.spin(1.0)  # let the subscription match before anything moves


def step() -> None:
    res = c.call(StepSimulation, "/step_simulation", timeout=30.0, steps=STEPS)
    assert res is not None and res.result.result == Result.RESULT_OK, res


def wheels(left: float, right: float) -> None:
    c.publish(msg.SetWheelVelocity, "/bot_setWheelVelocity", left_wheel=left, right_wheel=right)
    c.spin(0.02)  # the command is queued before the step request that follows


def pose() -> tuple[float, float, float]:
    p = c.call(GetEntityState, "/get_entity_state", entity="bot").state.pose
    q = p.orientation
    return p.position.x, p.position.y, math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y ** 2 + q.z ** 2))


def touching(part: str) -> bool:
    return c.call(srv.GetCollisionState, "/bot_get_collision_state", name="", part=part).collision_state


drive_steps, wheel_on_floor = 0, []
for (left, right), seconds in DRIVE:
    for _ in range(round(seconds / 0.1)):
        wheels(left, right)
        step()
        drive_steps += STEPS
    wheel_on_floor.append((touching("wheel_l_link"), touching("caster_back_link")))
c.spin(1.0)  # every message published during the drive has arrived
during_drive = [todict(h) for h in hits]
start = pose()

push_steps = 0
for _ in range(70):  # 7 s: about 4 s to reach the wall, then pushing into it
    x, y, yaw = pose()
    error = math.atan2(TARGET[1] - y, TARGET[0] - x) - yaw
    error = math.atan2(math.sin(error), math.cos(error))
    wheels(5.0 - 4.0 * error, 5.0 + 4.0 * error)
    step()
    push_steps += STEPS
end = pose()
pressed = touching("base_link")
wheels(0.0, 0.0)
step()
c.spin(1.0)
emit({"drive_steps": drive_steps, "push_steps": push_steps, "wheel_on_floor": wheel_on_floor,
      "during_drive": during_drive, "after_drive": [todict(h) for h in hits[len(during_drive):]],
      "start": start, "end": end, "pressed": pressed})
