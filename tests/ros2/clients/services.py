"""Call every sig_ros service of a robot (bot) and an object (cube); ground truth from simulation_interfaces."""

from common import Client, emit, todict
from sigcore_msgs import srv
from simulation_interfaces.srv import GetEntityState

c = Client("services_probe")
c.wait_ready()
out = {}


def call(name, srv_type, /, **fields):
    res = c.call(srv_type, name, **fields)
    out.setdefault(name, []).append(todict(res) if res is not None else None)
    return res


for agent in ("bot", "cube"):
    call(f"/{agent}_get_time", srv.GetTime)
    call(f"/{agent}_get_entities", srv.GetEntities)
    call(f"/{agent}_get_obj_position", srv.GetObjPosition, name="cube")
    call(f"/{agent}_get_obj_position", srv.GetObjPosition, name="")
    call(f"/{agent}_get_parts_position", srv.GetPartsPosition, name="bot", part="hand_link")
    call(f"/{agent}_get_joint_position", srv.GetJointPosition, name="bot", joint_name="shoulder_joint")
    call(f"/{agent}_get_rotation", srv.GetRotation, name="cube")
    call(f"/{agent}_get_angle_rotation", srv.GetAngleRotation, axis="z", x=1.0, y=0.0, z=0.0)
    call(f"/{agent}_get_joint_angle", srv.GetJointAngle, name="bot", name_arm="elbow_joint")
    call(f"/{agent}_get_all_joint_angles", srv.GetAllJointAngles, name="bot")
    call(f"/{agent}_get_mass", srv.GetMass, name="cube")
    call(f"/{agent}_get_angular_velocity", srv.GetAngularVelocity, name="cube")
    call(f"/{agent}_get_collision_state", srv.GetCollisionState, name="cube", part="main")
    call(f"/{agent}_is_grasped", srv.IsGrasped, name="cube")
    call(f"/{agent}_check_service", srv.CheckService, service_name="referee")
    call(f"/{agent}_connect_to_service", srv.ConnectToService, service_name="referee")
    call(f"/{agent}_send_msg_to_srv", srv.SendMsgToSrv, name="referee", msg="hi")
call("/bot_grasp_obj", srv.GraspObj, part="hand_link", obj="cube")  # 0.6 m away: refused
truth = {}
for name in ("bot", "cube"):
    res = c.call(GetEntityState, "/get_entity_state", entity=name)
    truth[name] = todict(res)
out["truth"] = truth
emit(out)
