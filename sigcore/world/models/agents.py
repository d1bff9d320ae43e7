"""The agents of a world: ``<robot>`` with its parts (drive, grippers, arms, gains; sensors are in
:mod:`.sensors`), ``<object>``, ``<human>`` and the bodiless ``<agent>``, and the ``Entity`` / ``AgentModel`` unions.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

from pydantic import Field, field_validator, model_validator

from ..exceptions import FieldError
from ..limits import MAX_SIZE
from .base import Description, EntityTags, Floats, Name, Pose, PoseField, Tags, Vec4, _Model
from .paths import WalkPath
from .sensors import Camera, Lidar

_CONTROLLER = "'package.module:Class' or a registered controller name"


class Drive(_Model):
    """``<drive>``: differential drive over two wheel joints of the robot's URDF."""

    type: Literal["differential"] = "differential"
    left: str = Field(description="left wheel joint name")
    right: str = Field(description="right wheel joint name")
    radius: float = Field(gt=0, le=5, description="wheel radius in [m]")
    separation: float = Field(gt=0, le=20, description="distance between the wheels in [m]")
    max_wheel_velocity: float = Field(default=20.0, gt=0, le=1000, description="wheel speed limit in [rad/s]")
    max_torque: float = Field(default=20.0, gt=0, le=100_000, description="wheel motor torque limit in [N m]")
    cmd_vel_timeout: float = Field(default=0.5, ge=0, le=3600,
                                   description="the wheels stop when no cmd_vel came for this long (simulated "
                                               "time) in [s]; 0: never")
    casters: Tags | None = Field(default=None, description="space-separated URDF links that roll or slide on the "
                                                           "floor besides the wheels; default: the links whose "
                                                           "name contains 'caster'")


class Gripper(_Model):
    """``<gripper>``: a part that can grasp graspable objects within ``grasp_radius``."""

    part: str = Field(description="URDF link that holds grasped objects")
    grasp_radius: float = Field(default=0.1, gt=0, le=2,
                                description="max distance part origin to object's centre of mass [m]")
    side: Literal["left", "right"] | None = Field(default=None,
                                                  description="which arm, for sig_ros 'arm' names")


class Arm(_Model):
    """``<arm>``: a kinematic chain from ``base`` link to ``tip`` link (used by IK)."""

    name: Name = Field(description="arm name, unique within the robot")
    base: str = Field(description="URDF link where the chain starts")
    tip: str = Field(description="URDF link where the chain ends")


class Gains(_Model):
    """``<gains>``: servo gains of the joint actuators (all non-wheel joints)."""

    kp: float = Field(default=200.0, gt=0, le=100_000, description="position gain in [N m/rad]")
    kv: float = Field(default=10.0, ge=0, le=10_000, description="damping in [N m s/rad]")
    max_torque: float = Field(default=100.0, gt=0, le=100_000, description="actuator torque limit in [N m]")


class Robot(_Model):
    """``<robot>``: an articulated body from a URDF file."""

    kind: Literal["robot"] = "robot"
    name: Name = Field(description="unique agent name; prefixes its ROS 2 topics")
    urdf: Path = Field(description="URDF file, relative to the world file's directory")
    pose: PoseField = Field(default=Pose(), description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad]")
    controller: str | None = Field(default=None, description=_CONTROLLER)
    fixed: bool = Field(default=False, description="root link welded to the world")
    drive: Drive | None = None
    lidars: tuple[Lidar, ...] = ()
    cameras: tuple[Camera, ...] = ()
    grippers: tuple[Gripper, ...] = ()
    arms: tuple[Arm, ...] = ()
    gains: Gains = Gains()
    tags: EntityTags = Field(default=(), description="space-separated labels, e.g. 'trash can'")
    description: Description = Field(default="", description="human-readable description (get_entity_info)")


Shape = Literal["box", "sphere", "cylinder", "capsule"]
_SIZE_COUNT = {"box": 3, "sphere": 1, "cylinder": 2, "capsule": 2}
_SIZE_HELP = {
    "box": "'sx sy sz' (full lengths)",
    "sphere": "'radius'",
    "cylinder": "'radius length'",
    "capsule": "'radius length' (length of the cylindrical part)",
}


class Object(_Model):
    """``<object>``: a rigid body: a primitive shape, a mesh, or a URDF model."""

    kind: Literal["object"] = "object"
    name: Name = Field(description="unique agent name; prefixes its ROS 2 topics")
    shape: Shape | None = Field(default=None, description="primitive shape")
    size: Floats | None = Field(default=None, description="sizes of the shape in [m]")
    mesh: Path | None = Field(default=None, description="mesh file, relative to the world file's directory")
    urdf: Path | None = Field(default=None, description="URDF file, relative to the world file's directory")
    scale: float = Field(default=1.0, ge=1e-3, le=1e3, description="mesh or URDF scale factor (not for shapes)")
    mass: float = Field(default=1.0, gt=0, le=1e5, description="in [kg] (ignored when static)")
    static: bool = Field(default=False, description="fixed in place, not moved by physics")
    graspable: bool = Field(default=False, description="grippers may grasp it")
    tags: EntityTags = Field(default=(), description="space-separated labels, e.g. 'trash can'")
    description: Description = Field(default="", description="human-readable description (get_entity_info)")
    pose: PoseField = Field(default=Pose(), description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad]")
    color: Vec4 = Field(default=(0.7, 0.7, 0.7, 1.0), description="'r g b a', each from 0 to 1")
    friction: float = Field(default=1.0, ge=0, le=10, description="sliding friction coefficient")
    controller: str | None = Field(default=None, description=_CONTROLLER)

    @field_validator("color")
    @classmethod
    def _color(cls, v: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
        if not all(0 <= c <= 1 for c in v):
            got = " ".join(f"{c:g}" for c in v)
            raise ValueError(f"components must be in [0, 1], got {got}; valid: 'r g b a'")
        return v

    @model_validator(mode="after")
    def _geometry(self) -> Object:
        given = [k for k in ("shape", "mesh", "urdf") if getattr(self, k) is not None]
        if not given:
            raise ValueError("no geometry; valid: one of 'shape' (with 'size'), 'mesh' or 'urdf'")
        if len(given) > 1:
            raise FieldError(given[1], f"'{given[0]}' and '{given[1]}' are both given; an object has "
                                       "exactly one of 'shape', 'mesh' or 'urdf'")
        if self.shape is not None:
            if self.size is None:
                raise ValueError(f"shape '{self.shape}' needs 'size'; valid: {_SIZE_HELP[self.shape]}")
            if len(self.size) != _SIZE_COUNT[self.shape]:
                raise FieldError("size", f"expected {_SIZE_COUNT[self.shape]} numbers for a {self.shape}, "
                                         f"got {len(self.size)}; valid: {_SIZE_HELP[self.shape]} [m]")
            if any(not 0 < s <= MAX_SIZE for s in self.size):
                got = " ".join(f"{s:g}" for s in self.size)
                raise FieldError("size", f"sizes {got} are out of range; valid: each > 0 and <= {MAX_SIZE:g} [m]")
            if "scale" in self.model_fields_set:
                raise FieldError("scale", f"'scale' is only for 'mesh' and 'urdf' objects; a {self.shape} is "
                                          f"sized by 'size' ({_SIZE_HELP[self.shape]})")
        elif self.size is not None:
            raise FieldError("size", f"'size' is only for primitive shapes; a {given[0]} object uses 'scale'")
        return self


class Human(_Model):
    """``<human>``: a person: an articulated body with REP-155's links and joints, sized from ``height``
    (:mod:`sigcore.world.body`), held kinematically (``static``, the default) or a mannequin whose joints keep
    their angles."""

    kind: Literal["human"] = "human"
    name: Name = Field(description="unique agent name; prefixes its ROS 2 topics")
    pose: PoseField = Field(default=Pose(), description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad]")
    height: float = Field(default=1.7, gt=0.3, le=2.5, description="in [m]")
    mass: float = Field(default=70.0, gt=0, le=500, description="in [kg]")
    static: bool = Field(default=True, description="held kinematically (moved only through the API, never pushed "
                                                   "over); false: a mannequin that falls and topples")
    controller: str | None = Field(default=None, description=_CONTROLLER)
    tags: EntityTags = Field(default=(), description="space-separated labels, e.g. 'trash can'")
    description: Description = Field(default="", description="human-readable description (get_entity_info)")
    path: WalkPath | None = Field(default=None, description="the <path> it walks from the start (sigcore.sim.paths)")


class BareAgent(_Model):
    """``<agent>``: an agent with no body, e.g. a moderator."""

    kind: Literal["agent"] = "agent"
    name: Name = Field(description="unique agent name; prefixes its ROS 2 topics")
    controller: str | None = Field(default=None, description=_CONTROLLER)


Entity = Robot | Object | Human
AgentModel = Robot | Object | Human | BareAgent
