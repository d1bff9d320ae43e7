"""Publish each sig_ros topic and observe its effect through services (robot 'bot', objects ball/heavy)."""

import math
import time

from common import Client, emit, todict
from rosgraph_msgs.msg import Clock
from sigcore_msgs import msg, srv
from simulation_interfaces.srv import GetEntityState

c = Client("topics_probe")
c.wait_ready()
out = {}


def state(name):
    return todict(c.call(GetEntityState, "/get_entity_state", entity=name).state)


def pos(name):
    p = state(name)["pose"]["position"]
    return [p["x"], p["y"], p["z"]]


clocks = c.listen(Clock, "/clock")
c.wait_for(lambda: bool(clocks), 10.0)


def sim_now():
    return clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9


def settle(seconds=0.3):
    """Let ``seconds`` of simulated time pass (whatever the machine's load does to the real-time pacing)."""
    end = sim_now() + seconds
    c.wait_for(lambda: sim_now() >= end, 10.0 + 3 * seconds)


# positions and orientations (ball: dynamic sphere)
c.publish(msg.EntityFlag, "/ball_setGravityMode", name="", flag=False)
c.publish(msg.EntityVector, "/ball_setPosition", name="", x=-1.0, y=1.0, z=1.0)
settle()
out["setGravityMode+setPosition"] = pos("ball")
c.publish(msg.EntityVector, "/bot_setVelocity", name="ball", x=0.0, y=0.0, z=0.5)
settle(0.4)
out["setVelocity_z"] = pos("ball")[2]
c.publish(msg.EntityVector, "/ball_setVelocity", name="", x=0.0, y=0.0, z=0.0)
c.publish(msg.EntityVector, "/ball_setAngularVelocity", name="", x=0.0, y=0.0, z=3.0)
settle(0.1)
out["setAngularVelocity"] = todict(c.call(srv.GetAngularVelocity, "/ball_get_angular_velocity", name=""))
c.publish(msg.EntityQuaternion, "/ball_setRotation", name="heavy", qw=math.cos(0.25), qx=0.0, qy=0.0,
          qz=math.sin(0.25))
settle()
out["setRotation"] = todict(c.call(srv.GetRotation, "/ball_get_rotation", name="heavy"))
c.publish(msg.EntityAxisAngle, "/heavy_setAxisAndAngle", name="", axis_x=0.0, axis_y=0.0, axis_z=1.0, angle=1.0)
settle()
out["setAxisAndAngle"] = todict(c.call(srv.GetRotation, "/ball_get_rotation", name="heavy"))
c.publish(msg.EntityMass, "/heavy_setMass", name="", mass=7.5)
settle(0.1)
out["setMass"] = todict(c.call(srv.GetMass, "/heavy_get_mass", name=""))
# forces on the floating ball (gravity off): each should change its velocity
c.publish(msg.EntityVector, "/ball_setAngularVelocity", name="", x=0.0, y=0.0, z=0.0)
forces = {}
for topic, cls, fields in (
        ("_setForce", msg.EntityVector, {"x": 30.0}),
        ("_addForce", msg.EntityVector, {"x": 30.0}),
        ("_addRelForce", msg.EntityVector, {"x": 30.0}),
        ("_setAccel", msg.EntityVector, {"x": 100.0}),
        ("_addForceAtPos", msg.EntityForceAtPos, {"x": 30.0}),
        ("_addForceAtRelPos", msg.EntityForceAtPos, {"x": 30.0}),
        ("_addRelForceAtPos", msg.EntityForceAtPos, {"x": 30.0}),
        ("_addRelForceAtRelPos", msg.EntityForceAtPos, {"x": 30.0}),
        ("_addForceToParts", msg.PartForce, {"x": 30.0, "part": "main"}),
        ("_setTorque", msg.EntityVector, {"z": 0.05})):
    c.publish(msg.EntityVector, "/ball_setVelocity", name="", x=0.0, y=0.0, z=0.0)
    c.publish(msg.EntityVector, "/ball_setAngularVelocity", name="", x=0.0, y=0.0, z=0.0)
    c.publish(msg.EntityVector, "/ball_setPosition", name="", x=-1.0, y=1.0, z=1.0)
    # the earlier spin left the ball at a yaw that depends on timing; a body-frame force must point along world x
    c.publish(msg.EntityQuaternion, "/ball_setRotation", name="", qw=1.0, qx=0.0, qy=0.0, qz=0.0)
    settle(0.15)
    c.publish(cls, f"/ball{topic}", name="", **fields)
    settle(0.15)
    s = state("ball")
    seen = [s["twist"]["linear"]["x"], s["twist"]["angular"]["z"]]
    # a topic and the services are not ordered: under the load of a parallel test run a command message has reached
    # the simulation after 0.15 s of simulated time (seen once); look again for up to 5 s (the ball floats without
    # gravity or friction, so an effect, once there, stays)
    deadline = time.monotonic() + 5.0
    while seen[1 if topic == "_setTorque" else 0] <= 0.01 and time.monotonic() < deadline:
        settle(0.05)
        s = state("ball")
        seen = [s["twist"]["linear"]["x"], s["twist"]["angular"]["z"]]
    forces[topic] = seen
out["forces"] = forces
# modes: dynamics off holds the ball where it is put even with gravity back on
c.publish(msg.EntityFlag, "/ball_setGravityMode", name="", flag=True)
c.publish(msg.EntityFlag, "/ball_setDynamicsMode", name="", flag=False)
c.publish(msg.EntityVector, "/ball_setPosition", name="", x=-1.0, y=1.0, z=0.8)
settle(0.5)
out["setDynamicsMode_off_z"] = pos("ball")[2]
c.publish(msg.EntityFlag, "/ball_setDynamicsMode", name="", flag=True)
settle(0.8)
out["setDynamicsMode_on_z"] = pos("ball")[2]
# collisions off: the heavy box falls through the floor
c.publish(msg.EntityFlag, "/heavy_setCollisionEnable", name="", flag=False)
settle(0.8)
out["setCollisionEnable_off_z"] = pos("heavy")[2]
# the robot's joints and wheels
def elbow():
    return todict(c.call(srv.GetJointAngle, "/bot_get_joint_angle", name="", name_arm="elbow_joint"))


def set_until(msg_type, topic, check, timeout=10.0, **fields):
    """Publish a command that sets a state (so sending it again changes nothing) every 0.1 s of simulated time
    until ``check()``, at most ``timeout`` [s] of wall time: on a loaded machine the first message on a new topic can
    be lost while the simulation's subscription still matches this publisher (seen once with 4 test workers)."""
    end = time.monotonic() + timeout
    c.publish(msg_type, topic, **fields)
    settle(0.1)
    while not check() and time.monotonic() < end:
        c.publish(msg_type, topic, **fields)
        settle(0.1)


set_until(msg.SetJointAngle, "/bot_setJointAngle", lambda: abs(elbow()["angle"] - 0.7) < 0.05, name="",
          joint_name="elbow_joint", angle=0.7)
out["setJointAngle"] = elbow()
set_until(msg.SetJointQuaternion, "/bot_setJointQuaternion", lambda: abs(elbow()["angle"] - 0.4) < 0.05, name="",
          joint_name="elbow_joint", qw=math.cos(0.2), qx=0.0, qy=math.sin(0.2), qz=0.0, offset=False)
out["setJointQuaternion"] = elbow()
before = todict(c.call(srv.GetJointAngle, "/bot_get_joint_angle", name="", name_arm="shoulder_joint"))["angle"]
c.publish(msg.SetJointVelocity, "/bot_setJointVelocity", joint_name="shoulder_joint", angular_velocity=1.0, max=0.0)
settle(0.5)
after = todict(c.call(srv.GetJointAngle, "/bot_get_joint_angle", name="", name_arm="shoulder_joint"))["angle"]
out["setJointVelocity_delta"] = after - before
c.publish(msg.SetJointVelocity, "/bot_setJointVelocity", joint_name="shoulder_joint", angular_velocity=0.0, max=0.0)
c.publish(msg.AddJointTorque, "/bot_addJointTorque", name="", joint_name="elbow_joint", torque=5.0)
settle(0.1)
out["addJointTorque_refusals_checked_in_log"] = True
c.publish(msg.SetWheel, "/bot_setWheel", wheel_radius=0.1, wheel_distance=0.36)
c.publish(msg.SetOwner, "/bot_setOwner", name="cube", part="main", owner="bot")
x0 = pos("bot")[0]
c.publish(msg.SetWheelVelocity, "/bot_setWheelVelocity", left_wheel=4.0, right_wheel=4.0)
settle(1.0)
c.publish(msg.SetWheelVelocity, "/bot_setWheelVelocity", left_wheel=0.0, right_wheel=0.0)
out["setWheelVelocity_dx"] = pos("bot")[0] - x0
# grasp through the service, then _releaseObj
hand = todict(c.call(srv.GetPartsPosition, "/bot_get_parts_position", name="", part="hand_link"))
c.publish(msg.EntityFlag, "/cube_setGravityMode", name="", flag=False)  # float where it is put,
c.publish(msg.EntityFlag, "/cube_setCollisionEnable", name="", flag=False)  # not pushed out of the hand
c.publish(msg.EntityVector, "/cube_setVelocity", name="", x=0.0, y=0.0, z=0.0)
c.publish(msg.EntityVector, "/cube_setPosition", name="", x=hand["pos_x"], y=hand["pos_y"], z=hand["pos_z"])
settle(0.05)
out["cube_at_grasp"] = [pos("cube"), [hand["pos_x"], hand["pos_y"], hand["pos_z"]]]
out["grasp"] = todict(c.call(srv.GraspObj, "/bot_grasp_obj", part="hand_link", obj="cube"))
out["is_grasped_after_grasp"] = todict(c.call(srv.IsGrasped, "/bot_is_grasped", name="cube"))
c.publish(msg.ReleaseObj, "/bot_releaseObj", arm="hand_link")
settle(0.2)
out["is_grasped_after_release"] = todict(c.call(srv.IsGrasped, "/bot_is_grasped", name="cube"))
c.publish(msg.EntityFlag, "/cube_setGravityMode", name="", flag=True)
c.publish(msg.EntityFlag, "/cube_setCollisionEnable", name="", flag=True)
emit(out)
