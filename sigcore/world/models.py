"""The world, as strict pydantic models. SI units, z up, right-handed (REP-103).

Every model forbids unknown fields and is frozen. XML attributes arrive as strings; the ``Vec*`` types split
space-separated numbers. The parser (``parser.py``) maps each validation error back to ``file:line:column``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    field_validator,
    model_validator,
)

from .exceptions import FieldError
from .limits import MAX_ANGLE, MAX_COORDINATE, MAX_LIDAR_RANGE, MAX_SIZE, check_magnitudes, parse_floats
from .randomization import Located, Randomize
from .urdf import UrdfDocument, UrdfFiles

NAME_PATTERN = r"^[A-Za-z][A-Za-z0-9_]*$"
"""Entity names become ROS 2 topic names (``<agent>_setPosition``): a letter, then letters, digits, ``_``."""


MAX_GRAVITY = 1000.0
"""Longest gravity vector a world may ask for [m/s^2] (about 100 g); beyond it the engines diverge."""

def _numbers(count: int | None) -> BeforeValidator:
    def parse(value: object) -> object:
        if isinstance(value, str):
            return parse_floats(value, count)
        if isinstance(value, tuple | list):
            if count is not None and len(value) != count:
                raise ValueError(f"expected {count} numbers, got {len(value)}")
            for v in value:
                if isinstance(v, float) and not math.isfinite(v):
                    raise ValueError(f"numbers must be finite, got {v}")
        return value

    return BeforeValidator(parse)


_CONTROLLER = "'package.module:Class' or a registered controller name"

_FULL_TURN_SLACK = 1e-3
"""``fov`` values up to 2π + this [rad] are taken as 2π, so that ``fov="6.2832"`` means a full turn."""


def _full_turn(value: object) -> object:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return value  # pydantic reports it
    return 2 * math.pi if 2 * math.pi < number <= 2 * math.pi + _FULL_TURN_SLACK else value


Vec3 = Annotated[tuple[float, float, float], _numbers(3)]
Vec4 = Annotated[tuple[float, float, float, float], _numbers(4)]
Vec6 = Annotated[tuple[float, float, float, float, float, float], _numbers(6)]
Floats = Annotated[tuple[float, ...], _numbers(None)]
Name = Annotated[str, Field(pattern=NAME_PATTERN, max_length=64)]
Tags = Annotated[tuple[str, ...], BeforeValidator(lambda v: tuple(v.split()) if isinstance(v, str) else v)]

MAX_TAGS = 64
"""Most tags one entity or named pose may carry."""

MAX_TAG_LENGTH = 64
"""Longest tag [characters]."""

MAX_DESCRIPTION = 1000
"""Longest description of an entity or named pose [characters]."""


def check_tags(tags: tuple[str, ...]) -> tuple[str, ...]:
    """``tags`` if each is a non-empty printable word without whitespace, at most :data:`MAX_TAG_LENGTH`
    characters, and there are at most :data:`MAX_TAGS` of them.

    Raises:
        ValueError: naming the first tag that breaks a rule and the rule.
    """
    if len(tags) > MAX_TAGS:
        raise ValueError(f"{len(tags)} tags; valid: at most {MAX_TAGS}")
    for tag in tags:
        if not isinstance(tag, str) or not tag:
            raise ValueError(f"tag {tag!r} is empty or not text; valid: non-empty words")
        if len(tag) > MAX_TAG_LENGTH:
            raise ValueError(f"tag {tag[:20]!r}... has {len(tag)} characters; valid: at most {MAX_TAG_LENGTH}")
        if any(c.isspace() for c in tag) or not tag.isprintable():
            raise ValueError(f"tag {tag[:40]!r} holds whitespace or control characters; valid: one printable word "
                             "per tag")
    return tags


def check_description(text: str) -> str:
    """``text`` if it has at most :data:`MAX_DESCRIPTION` characters.

    Raises:
        ValueError: it is longer.
    """
    if len(text) > MAX_DESCRIPTION:
        raise ValueError(f"description of {len(text)} characters; valid: at most {MAX_DESCRIPTION}")
    return text


EntityTags = Annotated[Tags, AfterValidator(check_tags)]
Description = Annotated[str, AfterValidator(check_description)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, str_strip_whitespace=True, allow_inf_nan=False)


class Pose(_Model):
    """A pose: position [m] and roll/pitch/yaw [rad] (fixed axes x, y, z)."""

    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)

    @classmethod
    def parse(cls, value: object) -> object:
        """Accept ``"x y z roll pitch yaw"`` or ``"x y z"``."""
        if isinstance(value, str):
            parts = value.split()
            if len(parts) not in (3, 6):
                raise ValueError(f"expected 3 or 6 numbers, got {len(parts)} ({value!r}); "
                                 "valid: 'x y z' or 'x y z roll pitch yaw'")
            try:
                numbers = [float(p) for p in parts]
            except ValueError:
                raise ValueError(f"{value!r} is not numbers separated by spaces") from None
            if not all(math.isfinite(n) for n in numbers):
                raise ValueError(f"numbers must be finite, got {value!r}")
            check_magnitudes(tuple(numbers[:3]), MAX_COORDINATE, "m", "x, y, z")
            check_magnitudes(tuple(numbers[3:]), MAX_ANGLE, "rad", "roll, pitch, yaw")
            rpy = (numbers[3], numbers[4], numbers[5]) if len(numbers) == 6 else (0.0, 0.0, 0.0)
            return cls(xyz=(numbers[0], numbers[1], numbers[2]), rpy=rpy)
        return value


PoseField = Annotated[Pose, BeforeValidator(Pose.parse)]


class PluginConfig(Located):
    """``<plugin name="slam" agent="robot_000" .../>``: a feature plugin enabled for this world.

    Every other attribute is kept as a string in ``config``; the core validates them against the feature's
    ``config_model`` when the simulation creates the feature (``sigcore.world.plugin_config``).
    """

    name: Name = Field(description="plugin to enable, e.g. 'slam'")
    config: dict[str, str] = Field(default_factory=dict)


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


class Lidar(_Model):
    """``<lidar>``: a planar laser scanner on one link, rays in the link's x-y plane, counter-clockwise."""

    name: Name = Field(description="scanner name, unique within the robot")
    link: str = Field(description="URDF link the scanner sits on")
    beams: int = Field(default=360, ge=1, le=10000, description="rays per scan")
    fov: Annotated[float, BeforeValidator(_full_turn)] = Field(
        default=2 * math.pi, gt=0, le=2 * math.pi,
        description="field of view in [rad] (up to 2π + 0.001 means 2π)",
    )
    range: Annotated[tuple[float, float], _numbers(2)] = Field(
        default=(0.05, 10.0), description="'min max' distance in [m]"
    )
    rate: float = Field(default=10.0, gt=0, le=1000, description="scans per simulated second in [Hz]")
    noise: float = Field(default=0.0, ge=0, le=1, description="Gaussian range noise std-dev in [m]")

    @field_validator("range")
    @classmethod
    def _range(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not 0 <= v[0] < v[1] <= MAX_LIDAR_RANGE:
            raise ValueError(f"min {v[0]:g} and max {v[1]:g} do not satisfy 0 <= min < max <= "
                             f"{MAX_LIDAR_RANGE:g}; valid: 'min max' [m], e.g. '0.05 10'")
        return v


CameraKind = Literal["rgb", "depth", "rgbd"]


class Camera(_Model):
    """``<camera>``: a pinhole camera on one link (square pixels). Its body frame follows REP-103 (x forward, y left,
    z up) at ``pose`` in the link's frame; images are published in its optical frame (z forward, x right, y down)."""

    name: Name = Field(description="camera name, unique within the robot; names its topics and frames")
    link: str = Field(description="URDF link the camera sits on")
    pose: PoseField = Field(default=Pose(), description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad] in the "
                                                        "link's frame; the camera looks along its x")
    width: int = Field(default=320, ge=8, le=4096, description="image width in [px]")
    height: int = Field(default=240, ge=8, le=4096, description="image height in [px]")
    fov: float = Field(default=math.pi / 3, gt=0.01, lt=3.14,
                       description="horizontal field of view in [rad] (ignored when 'focal' is given)")
    focal: float | None = Field(default=None, gt=0, le=1e5, description="focal length in [px] (fx = fy)")
    principal: Annotated[tuple[float, float], _numbers(2)] | None = Field(
        default=None, description="'cx cy' principal point in [px]; default: the image centre, "
                                  "((width - 1) / 2, (height - 1) / 2)")
    near: float = Field(default=0.05, gt=0, le=100, description="nearest distance rendered in [m]")
    far: float = Field(default=10.0, gt=0, le=10000, description="farthest distance rendered in [m]; depth beyond "
                                                                 "it (or no hit) is +inf")
    rate: float = Field(default=15.0, gt=0, le=1000, description="images per simulated second in [Hz]")
    type: CameraKind = Field(default="rgbd", description="what it renders: rgb, depth or rgbd (both)")
    noise: float = Field(default=0.0, ge=0, le=1, description="Gaussian depth noise std-dev in [m]")

    @model_validator(mode="after")
    def _check(self) -> Camera:
        if self.near >= self.far:
            raise ValueError(f"near {self.near:g} must be less than far {self.far:g}; valid: e.g. near='0.05' "
                             "far='10'")
        if self.principal is not None:
            cx, cy = self.principal
            if not (0 <= cx <= self.width - 1 and 0 <= cy <= self.height - 1):
                raise FieldError("principal", f"principal point ({cx:g}, {cy:g}) lies outside the "
                                              f"{self.width}x{self.height} image; valid: 0 <= cx <= "
                                              f"{self.width - 1}, 0 <= cy <= {self.height - 1}")
        return self

    @property
    def intrinsics(self) -> tuple[float, float, float]:
        """``(f, cx, cy)`` [px]: the focal length and the principal point (pixel centres at integers)."""
        f = self.focal if self.focal is not None else (self.width / 2) / math.tan(self.fov / 2)
        cx, cy = self.principal if self.principal is not None else ((self.width - 1) / 2, (self.height - 1) / 2)
        return f, cx, cy

    @property
    def link_frame(self) -> str:
        """The camera's body frame (x forward), a child of :attr:`link` (unprefixed)."""
        return f"{self.name}_link"

    @property
    def optical_frame(self) -> str:
        """The camera's optical frame (z forward, x right), a child of :attr:`link_frame` (unprefixed)."""
        return f"{self.name}_optical_frame"


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
    """``<human>``: a person, modelled as a standing capsule with a head (kinematic unless told otherwise)."""

    kind: Literal["human"] = "human"
    name: Name = Field(description="unique agent name; prefixes its ROS 2 topics")
    pose: PoseField = Field(default=Pose(), description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad]")
    height: float = Field(default=1.7, gt=0.3, le=2.5, description="in [m]")
    mass: float = Field(default=70.0, gt=0, le=500, description="in [kg]")
    static: bool = Field(default=True, description="held in place (moved only through the API)")
    controller: str | None = Field(default=None, description=_CONTROLLER)
    tags: EntityTags = Field(default=(), description="space-separated labels, e.g. 'trash can'")
    description: Description = Field(default="", description="human-readable description (get_entity_info)")


class BareAgent(_Model):
    """``<agent>``: an agent with no body, e.g. a moderator."""

    kind: Literal["agent"] = "agent"
    name: Name = Field(description="unique agent name; prefixes its ROS 2 topics")
    controller: str | None = Field(default=None, description=_CONTROLLER)


Entity = Robot | Object | Human
AgentModel = Robot | Object | Human | BareAgent


class NamedPose(_Model):
    """``<named_pose>``: a pose in ``world`` with a purpose (a drop or pick pose, a navigation goal, a spawn
    point), listed by the simulation_interfaces service ``get_named_poses``."""

    name: Name = Field(description="unique among the named poses (a robot's '<robot>_start' is taken)")
    pose: PoseField = Field(description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad] in world")
    tags: EntityTags = Field(default=(), description="space-separated labels, e.g. 'drop navigation_goal'")
    description: Description = Field(default="", description="human-readable description")
    bounds: Vec6 | None = Field(default=None, description="'min_x min_y min_z max_x max_y max_z': an axis-aligned "
                                                          "box in world, as offsets from the pose's position [m]")

    @field_validator("bounds")
    @classmethod
    def _bounds(cls, v: tuple[float, ...] | None) -> tuple[float, ...] | None:
        if v is not None and not all(v[i] < v[i + 3] for i in range(3)):
            got = " ".join(f"{c:g}" for c in v)
            raise ValueError(f"{got} is not min < max on every axis; valid: 'min_x min_y min_z max_x max_y max_z' "
                             "[m], e.g. '-0.3 -0.3 0 0.3 0.3 1.5'")
        if v is not None:
            check_magnitudes(v, MAX_COORDINATE, "m", "offsets")
        return v


START_POSE_TAGS = ("spawn", "start")
"""Tags of the automatic named pose ``<robot>_start`` of every robot."""


def start_pose_name(robot: str) -> str:
    """The name of robot ``robot``'s automatic named pose (its pose in the world file)."""
    return f"{robot}_start"


class World(_Model):
    """``<world>``: the root element."""

    name: Name = Field(default="world", description="world name")
    timestep: float = Field(default=0.002, gt=0, le=0.1, description="physics step in [s]")
    gravity: Vec3 = Field(default=(0.0, 0.0, -9.81), description="'x y z' acceleration in [m/s^2]")
    seed: int = Field(default=0, ge=0, description="seed of sensor noise")
    description: str = Field(default="", max_length=500,
                             description="one line saying what the world is for (listed by get_available_worlds)")
    tags: EntityTags = Field(default=(), description="space-separated labels of the world, e.g. 'indoor home'")

    @field_validator("gravity")
    @classmethod
    def _gravity(cls, v: tuple[float, float, float]) -> tuple[float, float, float]:
        size = math.sqrt(sum(c * c for c in v))
        if size > MAX_GRAVITY:
            raise ValueError(f"gravity of {size:g} m/s^2 is beyond the engines' stable range; valid: a vector of "
                             f"length <= {MAX_GRAVITY:g} [m/s^2], e.g. '0 0 -9.81'")
        return v
    plugins: tuple[PluginConfig, ...] = ()
    agents: tuple[AgentModel, ...] = ()
    named_poses: tuple[NamedPose, ...] = ()
    randomize: Randomize | None = Field(default=None, description="what a seeded run draws (<randomize>)")
    source: Path = Path("<memory>")
    _locations: dict[tuple[str, str | None], tuple[int, int]] = PrivateAttr(default_factory=dict)
    _urdfs: UrdfFiles = PrivateAttr(default_factory=UrdfFiles)
    _sample_seed: int | None = PrivateAttr(default=None)

    def location(self, agent: str, attribute: str | None = None) -> tuple[int, int]:
        """``(line, column)`` of an agent's element, or of one of its attributes, or of a child element
        (``drive``, ``lidar:<name>``, ``arm:<name>``: its ``name`` attribute); ``""``: the ``<world>`` element;
        (0, 0) if unknown."""
        return self._locations.get((agent, attribute), self._locations.get((agent, None), (0, 0)))

    def record_locations(self, locations: dict[tuple[str, str | None], tuple[int, int]]) -> None:
        """Remember where each agent's element and attributes are in the file (the parser calls this)."""
        self._locations.update(locations)

    @property
    def base_dir(self) -> Path:
        """Directory that relative model paths are resolved against."""
        return self.source.parent

    def resolve(self, path: Path) -> Path:
        """``path`` relative to the world file's directory."""
        return path if path.is_absolute() else (self.base_dir / path)

    def agent(self, name: str) -> AgentModel:
        """The agent called ``name``; ``KeyError`` listing valid names otherwise."""
        for a in self.agents:
            if a.name == name:
                return a
        raise KeyError(f"no agent '{name}'; agents: {', '.join(a.name for a in self.agents)}")

    @property
    def entities(self) -> tuple[Entity, ...]:
        """Agents with a body (robots, objects, humans)."""
        return tuple(a for a in self.agents if not isinstance(a, BareAgent))

    def all_named_poses(self) -> tuple[NamedPose, ...]:
        """The ``<named_pose>`` elements, then each robot's start pose ``<robot>_start`` (tags ``spawn start``,
        its ``pose`` attribute, no bounds)."""
        starts = tuple(NamedPose.model_construct(name=start_pose_name(r.name), pose=r.pose, tags=START_POSE_TAGS,
                                                 description=f"start pose of robot {r.name} (world file)",
                                                 bounds=None)
                       for r in self.agents if isinstance(r, Robot))
        return self.named_poses + starts

    def plugin(self, name: str) -> PluginConfig | None:
        """The ``<plugin name=...>`` entry, if enabled."""
        return next((p for p in self.plugins if p.name == name), None)

    def urdf(self, what: str | Path) -> UrdfDocument:
        """The parsed URDF of agent ``what`` (a name) or of file ``what`` (a ``Path``, relative to the world
        file's directory), shared by everyone: each file is read and parsed once per world (by the parser, or
        here on first use). Users that rewrite it take :meth:`UrdfDocument.copy_root`.

        Raises:
            KeyError: no agent ``what``, or it has no URDF; the message lists the agents that have one.
            UrdfError: the file cannot be read or is not XML.
        """
        if isinstance(what, Path):
            return self._urdfs.get(self.resolve(what))
        with_urdf = [a.name for a in self.agents if isinstance(a, Robot | Object) and a.urdf is not None]
        agent = next((a for a in self.agents if a.name == what), None)
        if agent is None:
            raise KeyError(f"no agent '{what}'; agents with a URDF: {', '.join(with_urdf) or 'none'}")
        if not isinstance(agent, Robot | Object) or agent.urdf is None:
            raise KeyError(f"agent '{what}' has no URDF; agents with one: {', '.join(with_urdf) or 'none'}")
        return self._urdfs.get(self.resolve(agent.urdf))

    def with_agents(self, agents: tuple[AgentModel, ...]) -> World:
        """This world with ``agents`` instead of its own (spawning and deleting while running): the same file,
        locations and shared URDF documents; the agents are not validated again (the caller has)."""
        copy = self.model_copy(update={"agents": tuple(agents)})
        copy._locations = self._locations
        copy._urdfs = self._urdfs
        return copy

    @property
    def sample_seed(self) -> int | None:
        """The seed this world was drawn with (:func:`sigcore.world.randomize.sample`, ``sigcore run --seed``);
        None: the file as written."""
        return self._sample_seed

    def drawn(self, agents: tuple[AgentModel, ...], seed: int) -> World:
        """This world with ``agents`` drawn by its ``<randomize>`` with ``seed`` (:attr:`sample_seed`): the same
        file, locations and shared URDF documents; the caller has validated the agents."""
        copy = self.with_agents(agents)
        copy._sample_seed = seed
        return copy

    def share_urdfs(self, files: UrdfFiles) -> None:
        """Use the URDF documents ``files`` already read (the parser calls this, so files are read once)."""
        self._urdfs = files


def valid_name(name: str) -> bool:
    """Whether ``name`` is a valid entity name."""
    return re.fullmatch(NAME_PATTERN, name) is not None


@dataclass(frozen=True)
class Spawnable:
    """A model that ``SpawnRequest.uri`` may name as ``model://NAME`` (``get_spawnables`` lists them).

    Attributes:
        name: The ``NAME`` of ``model://NAME``.
        description: What it is, for people.
        element: The world-format element that defines it (``<robot urdf="sigbot.urdf">...</robot>``), with
            relative paths starting at ``base``.
        base: Folder that relative paths in ``element`` start from.
        origin: Who offers it (``worlds/models`` or a plugin's name).
        bounds: Its axis-aligned bounds around its origin, ``(min xyz, max xyz)`` [m], if known.
    """

    name: str
    description: str
    element: str
    base: str
    origin: str = "worlds/models"
    bounds: tuple[tuple[float, float, float], tuple[float, float, float]] | None = field(default=None)

    @property
    def uri(self) -> str:
        """``model://NAME``."""
        return f"model://{self.name}"
