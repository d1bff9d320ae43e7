"""The world-level models: the ``<world>`` root (physics settings, agents, named poses, ``<randomize>``, shared
URDF documents), ``<plugin>`` entries and ``<named_pose>``, with the robots' automatic start poses.
"""

from __future__ import annotations

import math
from pathlib import Path

from pydantic import Field, PrivateAttr, field_validator

from ..body import human_body, human_urdf
from ..limits import MAX_COORDINATE, check_magnitudes
from ..randomization import Located, Randomize
from ..urdf import UrdfDocument, UrdfFiles
from .agents import AgentModel, BareAgent, Entity, Human, Object, Robot
from .base import Description, EntityTags, Name, PoseField, Vec3, Vec6, _Model

MAX_GRAVITY = 1000.0
"""Longest gravity vector a world may ask for [m/s^2] (about 100 g); beyond it the engines diverge."""


class PluginConfig(Located):
    """``<plugin name="slam" agent="robot_000" .../>``: a feature plugin enabled for this world.

    Every other attribute is kept as a string in ``config``; the core validates them against the feature's
    ``config_model`` when the simulation creates the feature (``sigcore.world.plugin_config``).
    """

    name: Name = Field(description="plugin to enable, e.g. 'slam'")
    config: dict[str, str] = Field(default_factory=dict)


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
        with_urdf = [a.name for a in self.agents
                     if isinstance(a, Human) or (isinstance(a, Robot | Object) and a.urdf is not None)]
        agent = next((a for a in self.agents if a.name == what), None)
        if agent is None:
            raise KeyError(f"no agent '{what}'; agents with a URDF: {', '.join(with_urdf) or 'none'}")
        if isinstance(agent, Human):
            return self._urdfs.generated(("human", agent.height, agent.mass),
                                         Path(f"<body of a {agent.height:g} m person>.urdf"),
                                         lambda: human_urdf(human_body(agent.height, agent.mass)))
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
