"""A batch of bad requests (unknown names, NaN, inf, wrong state): every one answered with an error; the
simulation keeps running."""

import math

from common import Client, emit, todict
from rosgraph_msgs.msg import Clock
from sigcore_msgs import msg, srv
from simulation_interfaces.srv import DeleteEntity, GetEntityState, SetEntityState, SpawnEntity, StepSimulation

c = Client("fuzz_probe")
c.wait_ready()
nan, inf = math.nan, math.inf
answers = []


def ask(name, srv_type, /, **fields):
    res = c.call(srv_type, name, **fields)
    answers.append({"call": name, "fields": {k: str(v) for k, v in fields.items()},
                    "response": todict(res) if res is not None else None})


t0 = todict(c.call(srv.GetTime, "/bot_get_time"))["time"]
ask("/bot_get_obj_position", srv.GetObjPosition, name="nobody")
ask("/cube_get_obj_position", srv.GetObjPosition, name="moderator")  # a bare agent has no body
ask("/bot_get_parts_position", srv.GetPartsPosition, name="bot", part="no_such_link")
ask("/bot_get_joint_position", srv.GetJointPosition, name="bot", joint_name="no_joint")
ask("/bot_get_joint_angle", srv.GetJointAngle, name="cube", name_arm="elbow_joint")  # not a robot
ask("/bot_get_joint_angle", srv.GetJointAngle, name="bot", name_arm="")
ask("/bot_get_angle_rotation", srv.GetAngleRotation, axis="w", x=1.0, y=0.0, z=0.0)
ask("/bot_get_angle_rotation", srv.GetAngleRotation, axis="x", x=nan, y=0.0, z=0.0)
ask("/bot_get_angle_rotation", srv.GetAngleRotation, axis="x", x=0.0, y=0.0, z=0.0)
ask("/bot_get_mass", srv.GetMass, name="ghost")
ask("/bot_get_collision_state", srv.GetCollisionState, name="cube", part="nope")
ask("/bot_grasp_obj", srv.GraspObj, part="nope", obj="cube")
ask("/bot_grasp_obj", srv.GraspObj, part="hand_link", obj="wall")
ask("/bot_grasp_obj", srv.GraspObj, part="hand_link", obj="ghost")
ask("/bot_connect_to_service", srv.ConnectToService, service_name="")
ask("/bot_send_msg_to_srv", srv.SendMsgToSrv, name="referee", msg="x")
ask("/get_entity_state", GetEntityState, entity="ghost")
ask("/set_entity_state", SetEntityState, entity="ball", **{"state.pose.position.x": nan,
                                                             "state.pose.orientation.w": 1.0})
ask("/set_entity_state", SetEntityState, entity="ball", **{"state.pose.orientation.w": 0.0})
ask("/set_entity_state", SetEntityState, entity="wall", **{"state.pose.orientation.w": 1.0,
                                                             "state.twist.linear.x": 1.0})
ask("/set_entity_state", SetEntityState, entity="ghost")
ask("/step_simulation", StepSimulation, steps=10)  # the simulation is playing
ask("/spawn_entity", SpawnEntity, name="new_box", uri="box.urdf")
ask("/delete_entity", DeleteEntity, entity="ghost")
# bad topic messages: refused (logged once), never fatal
for _ in range(3):
    c.publish(msg.EntityVector, "/ball_setPosition", name="", x=nan, y=0.0, z=1.0)
    c.publish(msg.EntityVector, "/ball_setVelocity", name="ghost", x=1.0, y=0.0, z=0.0)
    c.publish(msg.EntityMass, "/cube_setMass", name="", mass=-1.0)
    c.publish(msg.EntityQuaternion, "/cube_setRotation", name="", qw=0.0, qx=0.0, qy=0.0, qz=0.0)
    c.publish(msg.SetWheelVelocity, "/bot_setWheelVelocity", left_wheel=inf, right_wheel=0.0)
    c.publish(msg.SetJointAngle, "/bot_setJointAngle", name="", joint_name="elbow_joint", angle=99.0)
    c.publish(msg.SendMsg, "/bot_sendMsg", to="ghost", content="boo")
c.spin(0.5)
clocks = c.listen(Clock, "/clock")
c.wait_for(lambda: len(clocks) >= 5, 10.0)
t1 = todict(c.call(srv.GetTime, "/bot_get_time"))["time"]
emit({"answers": answers, "t0": t0, "t1": t1, "clock": [m.clock.sec + m.clock.nanosec * 1e-9 for m in clocks]})
