"""Request, response and message types of the agent API (sig_ros names in CamelCase, fields in snake_case, SI).

These models are the single definition of every type: the ROS 2 interface package ``sigcore_msgs`` is generated
from them (``sigcore interfaces``), and every handler validates its request against them.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, GetCoreSchemaHandler, create_model
from pydantic_core import core_schema


class StandardMessage(dict[str, Any]):
    """A field holding a standard ROS message (its field dictionary, as :mod:`sigcore.publish` spells values);
    subclasses name the type in ``ros_type``. Empty: the message's defaults."""

    ros_type = ""

    @classmethod
    def __get_pydantic_core_schema__(cls, source: Any, handler: GetCoreSchemaHandler) -> core_schema.CoreSchema:
        return core_schema.no_info_after_validator_function(cls, core_schema.dict_schema())


class ImageFields(StandardMessage):
    """``sensor_msgs/Image`` fields."""

    ros_type = "sensor_msgs/Image"


class CameraInfoFields(StandardMessage):
    """``sensor_msgs/CameraInfo`` fields."""

    ros_type = "sensor_msgs/CameraInfo"


FIELD_TYPES: dict[Any, str] = {str: "string", float: "float64", bool: "bool", int: "int32",
                               list[str]: "string[]", list[float]: "float64[]",
                               ImageFields: ImageFields.ros_type, CameraInfoFields: CameraInfoFields.ros_type}
_DEFAULTS: dict[Any, Any] = {str: "", float: 0.0, bool: False, int: 0, ImageFields: ImageFields(),
                             CameraInfoFields: CameraInfoFields()}


class ApiModel(BaseModel):
    """Base of every API type: unknown fields are errors, numbers are not coerced from strings."""

    model_config = ConfigDict(extra="forbid", strict=False, frozen=True)


def _model(type_name: str, doc: str, /, **fields: Any) -> type[ApiModel]:
    spec: dict[str, Any] = {}
    for field, ftype in fields.items():
        default = _DEFAULTS.get(ftype)
        spec[field] = (ftype, default) if default is not None else (ftype, [])
    return create_model(type_name, __base__=ApiModel, __doc__=doc, **spec)


VEC = {"x": float, "y": float, "z": float}
POS = {"pos_x": float, "pos_y": float, "pos_z": float}
QUAT = {"qw": float, "qx": float, "qy": float, "qz": float}
RESULT = {"success": bool, "message": str}

# ----------------------------------------------------------------- messages the agent publishes
OnRecvMsg = _model("OnRecvMsg", "A text message reached the agent.", sender=str, content=str)
OnCollisionMsg = _model("OnCollisionMsg", "A new contact: other entity `name` touches own part `part`.",
                        name=str, part=str)

# ----------------------------------------------------------------- messages the agent subscribes to
SetWheel = _model("SetWheel", "Differential-drive geometry [m]: used for cmd_vel and odometry from now on.",
                  wheel_radius=float, wheel_distance=float)
SetWheelVelocity = _model("SetWheelVelocity", "Wheel speeds [rad/s].", left_wheel=float, right_wheel=float)
SetJointVelocity = _model("SetJointVelocity", "Joint speed [rad/s] with a torque limit `max` [N m] (<= 0: "
                          "default).", joint_name=str, angular_velocity=float, max=float)
SetJointAngle = _model("SetJointAngle", "Set a joint angle [rad] instantly.", name=str, joint_name=str,
                       angle=float)
SetJointQuaternion = _model("SetJointQuaternion", "Set a revolute joint from a quaternion about its axis.",
                            name=str, joint_name=str, **QUAT, offset=bool)
AddJointTorque = _model("AddJointTorque", "Joint torque [N m] for the next step.", name=str, joint_name=str,
                        torque=float)
ReleaseObj = _model("ReleaseObj", "Release what a gripper holds (`arm`: gripper part, or left/right).", arm=str)
EntityVector = _model("EntityVector", "A vector for entity `name` (empty: this agent): position [m], "
                      "velocity [m/s], force [N]...", name=str, **VEC)
EntityForceAtPos = _model("EntityForceAtPos", "A force [N] at a point [m] on entity `name`.", name=str, **VEC,
                          **POS)
PartForce = _model("PartForce", "A force [N] on one part of entity `name`.", name=str, part=str, **VEC)
EntityQuaternion = _model("EntityQuaternion", "An orientation (w, x, y, z) for entity `name`.", name=str, **QUAT)
EntityAxisAngle = _model("EntityAxisAngle", "An orientation as axis and angle [rad].", name=str, axis_x=float,
                         axis_y=float, axis_z=float, angle=float)
EntityFlag = _model("EntityFlag", "Switch a mode of entity `name` on or off.", name=str, flag=bool)
EntityMass = _model("EntityMass", "Mass [kg] of entity `name`.", name=str, mass=float)
SetOwner = _model("SetOwner", "Record `owner` as the owner of a part of entity `name`.", name=str, part=str,
                  owner=str)
SendMsg = _model("SendMsg", "Send `content` to agent `to` (empty: every other agent).", to=str, content=str)

# ----------------------------------------------------------------- services: (request, response)
Empty = _model("Empty", "No fields.")
EntityName = _model("EntityName", "Entity `name` (empty: this agent).", name=str)
TimeResponse = _model("TimeResponse", "Simulation time [s].", time=float, **RESULT)
EntitiesResponse = _model("EntitiesResponse", "Every agent name.", entities_names=list[str], length=int, **RESULT)
PositionResponse = _model("PositionResponse", "A position [m].", **POS, **RESULT)
PartRequest = _model("PartRequest", "A part of entity `name`.", name=str, part=str)
JointRequest = _model("JointRequest", "A joint of entity `name`.", name=str, joint_name=str)
QuaternionResponse = _model("QuaternionResponse", "An orientation (w, x, y, z).", **QUAT, **RESULT)
AngleRotationRequest = _model("AngleRotationRequest", "A vector and a world axis (x, y or z).", axis=str, **VEC)
AngleResponse = _model("AngleResponse", "An angle [rad].", angle=float, **RESULT)
JointAngleRequest = _model("JointAngleRequest", "Joint `name_arm` of entity `name`.", name=str, name_arm=str)
AllJointAnglesResponse = _model("AllJointAnglesResponse", "Every joint angle [rad].", joint_name=list[str],
                                angle=list[float], length=int, **RESULT)
MassResponse = _model("MassResponse", "A mass [kg].", mass=float, **RESULT)
AngularVelocityResponse = _model("AngularVelocityResponse", "An angular velocity [rad/s].", v_x=float, v_y=float,
                                 v_z=float, **RESULT)
CollisionStateResponse = _model("CollisionStateResponse", "Whether the part touches something.",
                                collision_state=bool, **RESULT)
GraspRequest = _model("GraspRequest", "Grasp object `obj` with gripper part `part`.", part=str, obj=str)
OkResponse = _model("OkResponse", "Whether it was done.", ok=bool, **RESULT)
AnswerResponse = _model("AnswerResponse", "A yes/no answer.", answer=bool, **RESULT)
ServiceNameRequest = _model("ServiceNameRequest", "A service (e.g. a referee) by name.", service_name=str)
ConnectedResponse = _model("ConnectedResponse", "Whether this agent is connected to the service.", connected=bool,
                            **RESULT)
CameraRequest = _model("CameraRequest", "A camera of this robot by name (empty: its first <camera>).", camera=str)
CaptureViewResponse = _model("CaptureViewResponse", "One image of the camera now, stamped with the current step, "
                             "in its optical frame: `image` rgb8 (empty for a depth-only camera), `depth` 32FC1 in "
                             "[m] (empty for an rgb-only camera), and the intrinsics.", image=ImageFields,
                             depth=ImageFields, camera_info=CameraInfoFields, **RESULT)
DistanceResponse = _model("DistanceResponse", "Distance [m] from the camera to the nearest surface along its "
                          "optical axis (inf: nothing within its far distance).", distance=float, **RESULT)
SendToServiceRequest = _model("SendToServiceRequest", "Send `msg` to service `name`.", name=str, msg=str)


def field_types(model: type[BaseModel]) -> list[tuple[str, str]]:
    """``(ROS type, field name)`` of every field of ``model``, in order."""
    return [(FIELD_TYPES[f.annotation], name) for name, f in model.model_fields.items()]


def message_model(type_name: str, doc: str, /, **fields: Any) -> type[ApiModel]:
    """A message type for a feature's publication (``sigcore_msgs/msg/<type_name>`` when the feature is bundled):
    fields of the types of :data:`FIELD_TYPES`, with their zero defaults."""
    return _model(type_name, doc, **fields)
