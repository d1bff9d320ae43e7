"""The agent API table: every topic and service of every agent, typed, with its handler.

This table is the single source of truth: transports generate their endpoints from it, ``sigcore api WORLD``
prints it, and the ROS 2 interface package ``sigcore_msgs`` is generated from its types.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from pydantic import BaseModel

from ..publish import QosClass
from . import types as t
from .sources import Collisions, ReceivedMessages, Scans, Source

if TYPE_CHECKING:
    from ..sim.simulation import Simulation

Direction = Literal["service", "subscribe", "publish"]
"""``service``: request/response; ``subscribe``: the agent receives messages; ``publish``: the agent emits them."""

ALL = frozenset({"robot", "object", "human", "agent"})
ROBOT = frozenset({"robot"})
BODY = frozenset({"robot", "object", "human"})

Handler = Callable[["Simulation", str, Any], Any]
"""``handler(sim, agent_name, request) -> response fields (dict) or None``; raises ``ApiError`` to refuse."""


@dataclass(frozen=True)
class ApiEntry:
    """One endpoint pattern: ``<agent><suffix>`` for each agent whose kind is in ``kinds``.

    Attributes:
        suffix: The sig_ros suffix, e.g. ``_get_obj_position``.
        direction: ``service``, ``subscribe`` or ``publish``.
        ros_type: Interface type name in ``sigcore_msgs`` (CamelCase), or a full name such as
            ``sensor_msgs/msg/LaserScan`` for standard types.
        request: Message type (topics) or request type (services).
        response: Response type (services only).
        kinds: Agent kinds that have this endpoint.
        handler: Called for requests and received messages; ``None`` for published topics.
        doc: One line for humans.
        origin: ``sig_ros`` for the seeds' names, ``sigcore`` for our additions, or a plugin's name.
        source: ``publish`` entries only: where the values come from and which agents have the endpoint; the
            simulation declares one publication per agent from it (:mod:`sigcore.publish`).
        qos: ``publish`` entries only: the delivery class (:data:`sigcore.publish.QosClass`).
    """

    suffix: str
    direction: Direction
    ros_type: str
    request: type[BaseModel] | None
    response: type[BaseModel] | None
    kinds: frozenset[str]
    handler: Handler | None
    doc: str
    origin: str = "sig_ros"
    source: Source | None = None
    qos: QosClass = "events"

    def name_for(self, agent: str) -> str:
        """Endpoint name for ``agent``, e.g. ``robot_000_get_obj_position``."""
        return f"{agent}{self.suffix}"


_SEND_TO_SERVICE = ("send a text to a service this agent is connected to (both names are sig_ros's: "
                    "_send_msg_to_srv, _send_msg_to_service)")


def _entries() -> list[ApiEntry]:
    from . import handlers as h

    def pub(suffix: str, ros_type: str, msg: type[BaseModel] | None, kinds: frozenset[str], doc: str,
            source: Source, qos: QosClass = "events") -> ApiEntry:
        return ApiEntry(suffix, "publish", ros_type, msg, None, kinds, None, doc, source=source, qos=qos)

    def sub(suffix: str, ros_type: str, msg: type[BaseModel], kinds: frozenset[str], handler: Handler, doc: str,
            origin: str = "sig_ros") -> ApiEntry:
        return ApiEntry(suffix, "subscribe", ros_type, msg, None, kinds, handler, doc, origin)

    def srv(suffix: str, ros_type: str, req: type[BaseModel], res: type[BaseModel], kinds: frozenset[str],
            handler: Handler, doc: str, origin: str = "sig_ros") -> ApiEntry:
        return ApiEntry(suffix, "service", ros_type, req, res, kinds, handler, doc, origin)

    vec = t.EntityVector
    return [
        pub("_onRecvMsg", "OnRecvMsg", t.OnRecvMsg, ALL, "a text message reached the agent", ReceivedMessages()),
        pub("_onCollisionMsg", "OnCollisionMsg", t.OnCollisionMsg, BODY, "one part started touching another entity",
            Collisions()),
        pub("_scan", "sensor_msgs/msg/LaserScan", None, ROBOT, "each lidar scan (robots with a <lidar>)",
            Scans(), "sensor"),
        sub("_setWheel", "SetWheel", t.SetWheel, ROBOT, h.set_wheel,
            "set the drive geometry [m] used by cmd_vel and odometry (a reset restores the world file's)"),
        sub("_setWheelVelocity", "SetWheelVelocity", t.SetWheelVelocity, ROBOT, h.set_wheel_velocity,
            "wheel speeds [rad/s]"),
        sub("_setJointVelocity", "SetJointVelocity", t.SetJointVelocity, ROBOT, h.set_joint_velocity,
            "joint speed [rad/s] of this robot, torque limit max [N m]"),
        sub("_setJointAngle", "SetJointAngle", t.SetJointAngle, ALL, h.set_joint_angle,
            "set a joint angle [rad] instantly"),
        sub("_setJointTarget", "SetJointAngle", t.SetJointAngle, ALL, h.set_joint_target,
            "move a joint to an angle [rad] through its servo, over time", origin="sigcore"),
        sub("_setJointQuaternion", "SetJointQuaternion", t.SetJointQuaternion, ALL, h.set_joint_quaternion,
            "set a revolute joint from a quaternion"),
        sub("_addJointTorque", "AddJointTorque", t.AddJointTorque, ALL, h.add_joint_torque,
            "joint torque [N m] for the next step"),
        sub("_releaseObj", "ReleaseObj", t.ReleaseObj, ROBOT, h.release_obj, "release what a gripper holds"),
        sub("_setPosition", "EntityVector", vec, ALL, h.vector("set_position"), "teleport to a position [m]"),
        sub("_setVelocity", "EntityVector", vec, ALL, h.vector("set_velocity"), "set the velocity [m/s]"),
        sub("_setAngularVelocity", "EntityVector", vec, ALL, h.vector("set_angular_velocity"),
            "set the angular velocity [rad/s]"),
        sub("_setAccel", "EntityVector", vec, ALL, h.vector("set_accel"), "accelerate [m/s^2] for the next step"),
        sub("_setTorque", "EntityVector", vec, ALL, h.vector("set_torque"), "torque [N m] for the next step"),
        sub("_setForce", "EntityVector", vec, ALL, h.vector("set_force"), "force [N] for the next step"),
        sub("_addForce", "EntityVector", vec, ALL, h.vector("add_force"), "add a world-frame force [N]"),
        sub("_addRelForce", "EntityVector", vec, ALL, h.vector("add_rel_force"), "add an entity-frame force [N]"),
        sub("_addForceAtPos", "EntityForceAtPos", t.EntityForceAtPos, ALL, h.force_at("add_force_at_pos"),
            "world force [N] at a world point [m]"),
        sub("_addForceAtRelPos", "EntityForceAtPos", t.EntityForceAtPos, ALL, h.force_at("add_force_at_rel_pos"),
            "world force [N] at an entity-frame point [m]"),
        sub("_addRelForceAtPos", "EntityForceAtPos", t.EntityForceAtPos, ALL, h.force_at("add_rel_force_at_pos"),
            "entity-frame force [N] at a world point [m]"),
        sub("_addRelForceAtRelPos", "EntityForceAtPos", t.EntityForceAtPos, ALL,
            h.force_at("add_rel_force_at_rel_pos"), "entity-frame force [N] at an entity-frame point [m]"),
        sub("_addForceToParts", "PartForce", t.PartForce, ALL, h.add_force_to_parts, "force [N] on one part"),
        sub("_setRotation", "EntityQuaternion", t.EntityQuaternion, ALL, h.set_rotation,
            "set the orientation (w, x, y, z)"),
        sub("_setAxisAndAngle", "EntityAxisAngle", t.EntityAxisAngle, ALL, h.set_axis_and_angle,
            "set the orientation as axis and angle [rad]"),
        sub("_setCollisionEnable", "EntityFlag", t.EntityFlag, ALL, h.mode("collision"), "collisions on/off"),
        sub("_setGravityMode", "EntityFlag", t.EntityFlag, ALL, h.mode("gravity"), "gravity on/off"),
        sub("_setDynamicsMode", "EntityFlag", t.EntityFlag, ALL, h.mode("dynamics"),
            "dynamics on, or held kinematically"),
        sub("_setMass", "EntityMass", t.EntityMass, ALL, h.set_mass, "total mass [kg]"),
        sub("_setOwner", "SetOwner", t.SetOwner, ALL, h.set_owner, "record the owner of a part"),
        sub("_sendMsg", "SendMsg", t.SendMsg, ALL, h.send_msg, "send a text to another agent (empty: all)",
            origin="sigcore"),
        srv("_get_time", "GetTime", t.Empty, t.TimeResponse, ALL, h.get_time, "simulation time [s]"),
        srv("_get_entities", "GetEntities", t.Empty, t.EntitiesResponse, ALL, h.get_entities, "every agent name"),
        srv("_get_obj_position", "GetObjPosition", t.EntityName, t.PositionResponse, ALL, h.get_obj_position,
            "entity position [m]"),
        srv("_get_parts_position", "GetPartsPosition", t.PartRequest, t.PositionResponse, ALL,
            h.get_parts_position, "position of a part [m]"),
        srv("_get_joint_position", "GetJointPosition", t.JointRequest, t.PositionResponse, ALL,
            h.get_joint_position, "position of a joint anchor [m]"),
        srv("_get_rotation", "GetRotation", t.EntityName, t.QuaternionResponse, ALL, h.get_rotation,
            "orientation (w, x, y, z)"),
        srv("_get_angle_rotation", "GetAngleRotation", t.AngleRotationRequest, t.AngleResponse, ALL,
            h.get_angle_rotation, "angle [rad] between a vector and an axis (sig_ros returned its cosine)"),
        srv("_get_joint_angle", "GetJointAngle", t.JointAngleRequest, t.AngleResponse, ALL, h.get_joint_angle,
            "joint angle [rad]"),
        srv("_get_all_joint_angles", "GetAllJointAngles", t.EntityName, t.AllJointAnglesResponse, ALL,
            h.get_all_joint_angles, "every joint angle [rad]"),
        srv("_get_mass", "GetMass", t.EntityName, t.MassResponse, ALL, h.get_mass, "total mass [kg]"),
        srv("_get_angular_velocity", "GetAngularVelocity", t.EntityName, t.AngularVelocityResponse, ALL,
            h.get_angular_velocity, "angular velocity [rad/s]"),
        srv("_get_collision_state", "GetCollisionState", t.PartRequest, t.CollisionStateResponse, ALL,
            h.get_collision_state, "is that part (main = body) touching something"),
        srv("_get_collision_state_of_main_part", "GetCollisionStateOfMainPart", t.EntityName,
            t.CollisionStateResponse, ALL, h.get_collision_state_of_main_part,
            "is the main part of the agent (or of entity `name`) touching something"),
        srv("_grasp_obj", "GraspObj", t.GraspRequest, t.OkResponse, ROBOT, h.grasp_obj,
            "grasp obj with a gripper part: its centre of mass within the gripper's grasp_radius [m] of the part's "
            "origin (refusal reason in message)"),
        srv("_is_grasped", "IsGrasped", t.EntityName, t.AnswerResponse, ALL, h.is_grasped, "is the entity held"),
        srv("_check_service", "CheckService", t.ServiceNameRequest, t.ConnectedResponse, ALL, h.check_service,
            "is this agent connected to that service (e.g. the referee); names ignore case"),
        srv("_connect_to_service", "ConnectToService", t.ServiceNameRequest, t.ConnectedResponse, ALL,
            h.connect_to_service, "connect this agent to a service; names ignore case"),
        srv("_send_msg_to_srv", "SendMsgToSrv", t.SendToServiceRequest, t.OkResponse, ALL, h.send_msg_to_srv,
            _SEND_TO_SERVICE),
        srv("_send_msg_to_service", "SendMsgToSrv", t.SendToServiceRequest, t.OkResponse, ALL, h.send_msg_to_srv,
            _SEND_TO_SERVICE),
        srv("_captureView", "CaptureView", t.CameraRequest, t.CaptureViewResponse, ROBOT, h.capture_view,
            "one image of a camera now (SIGVerse's captureView): rgb8, depth 32FC1 [m] and CameraInfo",
            origin="sigcore"),
        srv("_distanceSensor", "DistanceSensor", t.CameraRequest, t.DistanceResponse, ROBOT, h.distance_sensor,
            "distance [m] along a camera's optical axis to the nearest surface (SIGVerse's distanceSensor)",
            origin="sigcore"),
    ]


_TABLE: list[ApiEntry] | None = None


def api_table() -> list[ApiEntry]:
    """The core's API entries (features may add theirs: :meth:`Simulation.api_entries`)."""
    global _TABLE
    if _TABLE is None:
        _TABLE = _entries()
    return _TABLE


def entries_for(kind: str, table: list[ApiEntry] | None = None) -> list[ApiEntry]:
    """Entries an agent of ``kind`` has."""
    return [e for e in (table if table is not None else api_table()) if kind in e.kinds]
