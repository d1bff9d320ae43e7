"""The world, as strict pydantic models. SI units, z up, right-handed (REP-103).

Every model forbids unknown fields and is frozen. XML attributes arrive as strings; the ``Vec*`` types split
space-separated numbers. The parser (``parser.py``) maps each validation error back to ``file:line:column``.
The models live by concept in the modules of this package (:mod:`.base`: field types, ``Pose`` and names;
:mod:`.sensors`; :mod:`.agents`; :mod:`.paths`: a person's ``<path>``; :mod:`.world`: the root and world-level
settings; :mod:`.spawnable`); import them from here.
"""

from .agents import AgentModel, Arm, BareAgent, Drive, Entity, Gains, Gripper, Human, Object, Robot, Shape
from .base import (
    MAX_DESCRIPTION,
    MAX_TAG_LENGTH,
    MAX_TAGS,
    NAME_PATTERN,
    Description,
    EntityTags,
    Floats,
    Name,
    Pose,
    PoseField,
    Tags,
    Vec3,
    Vec4,
    Vec6,
    check_description,
    check_tags,
    valid_name,
)
from .paths import MAX_PATH_SPEED, MIN_PATH_SPEED, WalkPath, Waypoint
from .sensors import Camera, CameraKind, Lidar
from .spawnable import Spawnable
from .world import MAX_GRAVITY, START_POSE_TAGS, NamedPose, PluginConfig, World, start_pose_name

__all__ = [
    "MAX_DESCRIPTION", "MAX_GRAVITY", "MAX_PATH_SPEED", "MAX_TAGS", "MAX_TAG_LENGTH", "MIN_PATH_SPEED",
    "NAME_PATTERN", "START_POSE_TAGS", "AgentModel", "Arm", "BareAgent", "Camera", "CameraKind", "Description",
    "Drive", "Entity", "EntityTags", "Floats", "Gains", "Gripper", "Human", "Lidar", "Name", "NamedPose", "Object",
    "PluginConfig", "Pose", "PoseField", "Robot", "Shape", "Spawnable", "Tags", "Vec3", "Vec4", "Vec6", "WalkPath",
    "Waypoint", "World", "check_description", "check_tags", "start_pose_name", "valid_name",
]
