"""World files: XML -> strict pydantic models with ``file:line:column`` in every error."""

from .exceptions import UrdfError, WorldError, WorldIssue
from .models import (
    Arm,
    BareAgent,
    Camera,
    Drive,
    Entity,
    Gains,
    Gripper,
    Human,
    Lidar,
    NamedPose,
    Object,
    PluginConfig,
    Pose,
    Robot,
    WalkPath,
    Waypoint,
    World,
)
from .parser import parse_world
from .urdf import UrdfDocument, UrdfFiles, UrdfJoint, UrdfModel, read_urdf

__all__ = [
    "Arm", "BareAgent", "Camera", "Drive", "Entity", "Gains", "Gripper", "Human", "Lidar", "NamedPose", "Object",
    "PluginConfig", "Pose", "Robot", "UrdfDocument", "UrdfError", "UrdfFiles", "UrdfJoint", "UrdfModel", "WalkPath",
    "Waypoint", "World", "WorldError", "WorldIssue", "parse_world", "read_urdf",
]
