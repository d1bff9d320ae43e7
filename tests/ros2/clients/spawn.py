"""Spawn and delete while running (tests/data/sim/world.xml): a URDF robot, a box and a namespaced spawnable robot
while PLAYING, their fall in lockstep, their endpoints, TF frames and one sig_ros service; bad requests; deletion.

Argument: the absolute path of worlds/models/sigbot/sigbot.urdf.
"""

import math
import sys

from common import Client, emit, todict
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import JointState
from sigcore_msgs import srv as sig
from simulation_interfaces.msg import EntityFilters, Resource, SimulationState
from simulation_interfaces.msg import SpawnEntity as SpawnMsg
from simulation_interfaces.srv import (
    DeleteEntity,
    GetEntities,
    GetEntitiesStates,
    GetEntityState,
    GetSimulationState,
    GetSimulatorFeatures,
    GetSpawnables,
    ResetSimulation,
    SetSimulationState,
    SpawnEntities,
    SpawnEntity,
    StepSimulation,
)
from tf2_msgs.msg import TFMessage

URDF = sys.argv[1]
BOX = '<object shape="box" size="0.1 0.1 0.1"/>'
SPHERICAL = ('<robot name="flyer"><link name="a"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" '
            'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link><link name="b"><inertial><mass value="1"/>'
            '<inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>'
            '<joint name="j" type="spherical"><parent link="a"/><child link="b"/></joint></robot>')
c = Client("spawn_probe")
c.wait_ready()
out: dict = {}


def pose(x: float, y: float, z: float, frame: str = "") -> PoseStamped:
    p = PoseStamped()
    p.header.frame_id = frame
    p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
    return p


def result(response) -> dict:
    if response is None:
        return {"result": None, "message": "no answer"}
    r = {"result": response.result.result, "message": response.result.error_message}
    if hasattr(response, "entity_name"):
        r["name"] = response.entity_name
    return r


def spawn(timeout: float = 30.0, **fields) -> dict:
    return result(c.call(SpawnEntity, "/spawn_entity", timeout=timeout, **fields))


def spawn_msg(name: str, uri: str = "", resource: str = "", at: PoseStamped | None = None, ns: str = "") -> SpawnMsg:
    return SpawnMsg(name=name, entity_resource=Resource(uri=uri, resource_string=resource),
                    initial_pose=at or pose(0.0, 0.0, 0.0), entity_namespace=ns)


def z_of(name: str) -> float | None:
    got = c.call(GetEntityState, "/get_entity_state", entity=name)
    return None if got is None or got.result.result != 1 else got.state.pose.position.z


def graph() -> set[str]:
    """The simulation node's topics and services."""
    return c.graph()


def all_poses() -> dict:
    got = c.call(GetEntitiesStates, "/get_entities_states", filters=EntityFilters())
    return {n: todict(s.pose) for n, s in zip(got.entities, got.states, strict=True)}


features = c.call(GetSimulatorFeatures, "/get_simulator_features").features
out["features"] = sorted(features.features)
out["formats"] = list(features.spawn_formats)
spawnables = c.call(GetSpawnables, "/get_spawnables", sources=["/nowhere"])
out["spawnables"] = {"result": result(spawnables), "uris": [s.uri for s in spawnables.spawnables],
                     "described": all(s.description for s in spawnables.spawnables)}
joint_states = c.listen(JointState, "/rover/joint_states", 100)
tfs = c.listen(TFMessage, "/tf", 1000)

# while PLAYING: a URDF robot and, in one call, a box and a namespaced spawnable robot, all in the air
out["state_at_spawn"] = c.call(GetSimulationState, "/get_simulation_state").state.state
out["rover"] = spawn(name="rover", uri=URDF, initial_pose=pose(1.0, 1.0, 0.3))
many = c.call(SpawnEntities, "/spawn_entities", timeout=30.0,
              spawn_requests=[spawn_msg("crate", resource=BOX, at=pose(1.0, -1.0, 0.8)),
                              spawn_msg("rover2", uri="model://sigbot", at=pose(-1.0, -1.0, 0.2), ns="/team1")])
out["many"] = {**result(many), "results": [{"result": r.result.result, "name": r.entity_name}
                                           for r in many.results]}
out["paused"] = c.call(SetSimulationState, "/set_simulation_state",
                       state=SimulationState(state=SimulationState.STATE_PAUSED)).result.result
out["z0"] = {n: z_of(n) for n in ("rover", "crate", "rover2")}
out["step"] = c.call(StepSimulation, "/step_simulation", timeout=120.0, steps=1500).result.result  # 3 s
out["z"] = {n: z_of(n) for n in ("rover", "crate", "rover2")}

# their endpoints, their frames and one sig_ros service of the new robot
wanted = {"/rover/joint_states", "/rover_get_obj_position", "/rover_setJointAngle", "/crate_get_obj_position",
          "/team1/rover2/joint_states", "/team1/rover2/cmd_vel", "/team1/rover2/odom",
          "/team1/rover2_get_obj_position", "/team1/rover2_onRecvMsg"}
c.wait_for(lambda: wanted <= graph(), 15.0)
out["appeared"] = sorted(wanted & graph())
c.call(StepSimulation, "/step_simulation", steps=100)
c.wait_for(lambda: bool(joint_states) and any(t.child_frame_id == "crate" for m in tfs for t in m.transforms), 5.0)
out["joint_states"] = len(joint_states[-1].name) if joint_states else 0
crate_tf = [t for m in tfs for t in m.transforms if t.child_frame_id == "crate"]
out["crate_tf"] = {"parent": crate_tf[-1].header.frame_id, "z": crate_tf[-1].transform.translation.z} \
    if crate_tf else None
position = c.call(sig.GetObjPosition, "/rover_get_obj_position", name="")
out["sigros"] = todict(position) if position is not None else None
position = c.call(sig.GetObjPosition, "/team1/rover2_get_obj_position", name="")
out["sigros_ns"] = todict(position) if position is not None else None

# bad requests while paused: each refused with its code; nothing existing moves
before = all_poses()
names_before = set(before)
out["bad"] = {
    "malformed": spawn(name="m", resource_string="<robot name='x'><link"),
    "unknown": spawn(name="n", uri="model://nope"),
    "taken": spawn(name="cube", resource_string=BOX),
    "nan": spawn(name="nanbox", resource_string=BOX, initial_pose=pose(math.nan, 0.0, 1.0)),
    "mesh": spawn(name="meshy", resource_string='<object mesh="/nonexistent/thing.obj"/>'),
    "joint": spawn(name="flyer", resource_string=SPHERICAL),
    "empty": spawn(name="e"),
    "namespace": spawn(name="nsb", resource_string=BOX, entity_namespace="bad ns"),
    "frame": spawn(name="f", resource_string=BOX, initial_pose=pose(0.0, 0.0, 1.0, "nowhere")),
}
out["unmoved"] = {n: p for n, p in all_poses().items() if n in names_before} == before
out["renamed"] = spawn(name="cube", resource_string=BOX, allow_renaming=True, initial_pose=pose(0.0, 2.0, 0.05))
many = c.call(SpawnEntities, "/spawn_entities", timeout=30.0,
              spawn_requests=[spawn_msg("good", resource=BOX, at=pose(0.0, -2.0, 0.05)),
                              spawn_msg("", uri="model://nope")])
out["partial"] = {**result(many), "results": [{"result": r.result.result, "name": r.entity_name}
                                              for r in many.results]}

# delete them: their endpoints go away
gone = ["rover", "crate", "rover2", out["renamed"].get("name", ""), "good"]
out["deleted"] = {n: result(c.call(DeleteEntity, "/delete_entity", timeout=30.0, entity=n)) for n in gone}
out["delete_again"] = result(c.call(DeleteEntity, "/delete_entity", entity="rover"))
c.wait_for(lambda: not (wanted & graph()), 15.0)
out["left"] = sorted(wanted & graph())
out["entities"] = list(c.call(GetEntities, "/get_entities", filters=EntityFilters()).entities)

# still running: a later spawn works, the reset scopes, stopped
out["later"] = spawn(name="late", resource_string=BOX, initial_pose=pose(0.0, 0.0, 1.5, "cube"))
out["late_z"] = z_of("late")
out["reset_state"] = result(c.call(ResetSimulation, "/reset_simulation", scope=ResetSimulation.Request.SCOPE_STATE))
out["after_state"] = list(c.call(GetEntities, "/get_entities", filters=EntityFilters()).entities)
out["reset_all"] = result(c.call(ResetSimulation, "/reset_simulation", scope=ResetSimulation.Request.SCOPE_DEFAULT))
out["after_all"] = list(c.call(GetEntities, "/get_entities", filters=EntityFilters()).entities)
c.call(SetSimulationState, "/set_simulation_state", state=SimulationState(state=SimulationState.STATE_STOPPED))
out["stopped"] = spawn(name="s", resource_string=BOX)
out["stopped_delete"] = result(c.call(DeleteEntity, "/delete_entity", entity="cube"))
c.call(SetSimulationState, "/set_simulation_state", state=SimulationState(state=SimulationState.STATE_PLAYING))
out["replay"] = spawn(name="again", resource_string=BOX, initial_pose=pose(0.0, -2.0, 0.3))
emit(out)
