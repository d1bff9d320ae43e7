"""Configuration of the ROS 2 transport: ``<plugin name="ros2" .../>`` in the world file (all optional).

Example::

    <plugin name="ros2" clock_rate="0" state_rate="50" sim_prefix="" sigros="true" standard="true"
            qos="/clock: best_effort; /robot_000/base_scan: best_effort depth=1"/>

The ``ros2`` feature only stores this configuration; the transport reads it when it starts.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Annotated

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, field_validator

from sigcore.feature import Feature, FeatureConfig
from sigcore.world import BareAgent
from sigcore.world.exceptions import FieldError
from sigcore.world.plugin_config import validate_plugin

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation
    from sigcore.world import World
    from sigcore.world.models import AgentModel

CLOCK_WALL_LIMIT = 200.0
"""Default most /clock messages per second of wall time [Hz] (see ``docs/ros2.md``, "The /clock policy")."""

QOS_WORDS = ("reliable", "best_effort", "volatile", "transient_local", "keep_all")
"""Words of a QoS override; ``depth=N`` sets a keep-last depth."""


class QosOverride(BaseModel):
    """A per-topic QoS override; ``None`` fields keep the default of the topic.

    Attributes:
        reliable: Reliable (True) or best effort (False).
        transient_local: Transient-local (True, latched) or volatile (False).
        depth: Keep-last depth; 0 means keep all.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    reliable: bool | None = None
    transient_local: bool | None = None
    depth: int | None = Field(default=None, ge=0, le=100_000)


def parse_qos(text: str) -> dict[str, QosOverride]:
    """Parse ``"/clock: best_effort; /robot_000/odom: reliable depth=5"`` into overrides by topic.

    Raises:
        ValueError: a malformed entry, naming it and the valid words.
    """
    out: dict[str, QosOverride] = {}
    for item in filter(None, (part.strip() for part in text.split(";"))):
        topic, sep, spec = item.partition(":")
        topic = topic.strip()
        if not sep or not re.fullmatch(r"/?[A-Za-z_][A-Za-z0-9_/]*", topic):
            raise ValueError(f"'{item}' is not 'TOPIC: WORDS'; valid: e.g. '/clock: best_effort depth=1'")
        fields: dict[str, object] = {}
        for word in spec.split():
            if word in ("reliable", "best_effort"):
                fields["reliable"] = word == "reliable"
            elif word in ("volatile", "transient_local"):
                fields["transient_local"] = word == "transient_local"
            elif word == "keep_all":
                fields["depth"] = 0
            elif re.fullmatch(r"depth=\d+", word):
                fields["depth"] = int(word.split("=")[1])
            else:
                raise ValueError(f"unknown word '{word}' for {topic}; valid: {', '.join(QOS_WORDS)}, depth=N")
        out[topic if topic.startswith("/") else "/" + topic] = QosOverride.model_validate(fields)
    return out


def _qos(value: object) -> object:
    return parse_qos(value) if isinstance(value, str) else value


QosField = Annotated[dict[str, QosOverride], BeforeValidator(_qos)]

AGENT_KINDS = {"robots": "robot", "objects": "object", "humans": "human", "agents": "agent"}
"""The kinds ``sigros_agents`` may name, and the agent kind each selects."""


def _words(value: object) -> object:
    return tuple(value.split()) if isinstance(value, str) else value


def _selection(words: tuple[str, ...]) -> tuple[str, ...]:
    """``words`` if each is ``all`` (alone), a kind, ``tag:NAME`` or a name (the world's names are checked by
    :func:`sigros_agents`)."""
    if not words:
        raise ValueError("empty; valid: 'auto', 'all', or agent names, kinds (robots, objects, humans, agents), "
                         "tag:NAME")
    if "all" in words and len(words) > 1:
        raise ValueError("'all' selects every agent: give it alone, or name agents, kinds or tags")
    for word in words:
        if not re.fullmatch(r"all|auto|tag:\S+|[A-Za-z][A-Za-z0-9_]*", word):
            raise ValueError(f"'{word}' is not an agent name, a kind or tag:NAME; valid: 'auto', 'all', agent names, "
                             "robots, objects, humans, agents, tag:NAME")
    return words


AgentSelection = Annotated[tuple[str, ...], BeforeValidator(_words), AfterValidator(_selection)]


class Ros2Config(FeatureConfig):
    """Settings of the ROS 2 transport: the attributes of ``<plugin name="ros2">``, validated by the core.

    Attributes:
        clock_rate: /clock publication rate [Hz of simulated time]; 0 publishes every step (the default), subject
            to ``clock_wall_limit``.
        clock_wall_limit: Most /clock messages per second of wall time [Hz]; a step whose state is published
            (``state_rate``) or a scan always has its /clock first; 0: no limit (every step).
        state_rate: Rate of /tf, odom and joint_states [Hz].
        entity_tf_rate: Rate of the ``world -> <entity>`` transforms of objects and humans on /tf [Hz]; 0: off.
        sim_prefix: Prefix of the simulation_interfaces services and action (e.g. ``/sim``; default: root).
        sigros: Create the sig_ros-compatible ``<agent>_<suffix>`` endpoints.
        sigros_agents: The agents that get them: ``auto`` (the default: every agent but the objects without a
            controller, see :func:`automatic`), ``all``, or agent names, kinds (``robots``, ``objects``,
            ``humans``, ``agents``) and ``tag:NAME`` (with ``auto`` or without); the others' entities still exist
            (TF, simulation_interfaces) and are reached through the shared ``/sigcore/sigros/<function>``
            endpoints.
        standard: Create the idiomatic topics (/clock, /tf, cmd_vel, odom, joint_states, scans).
        qos: Per-topic QoS overrides, by absolute topic name.
    """

    clock_rate: float = Field(default=0.0, ge=0.0, description="/clock publication rate in [Hz]; 0: every step")
    clock_wall_limit: float = Field(default=CLOCK_WALL_LIMIT, ge=0.0, le=1e6,
                                    description="at most this many /clock messages per second of wall time in [Hz], "
                                                "besides the one before each stamped state message; 0: no limit")
    state_rate: float = Field(default=50.0, gt=0.0, description="rate of /tf, odom and joint_states in [Hz]")
    entity_tf_rate: float = Field(default=10.0, ge=0.0, le=1e4,
                                  description="rate of the world -> <entity> transforms of objects and humans on "
                                              "/tf in [Hz]; 0: off")
    sim_prefix: str = Field(default="", description="namespace of the simulation_interfaces services, e.g. "
                                                    "'/sim' (default: root)")
    sigros: bool = Field(default=True, description="create the sig_ros-compatible <agent>_<suffix> endpoints")
    sigros_agents: AgentSelection = Field(default=("auto",), description="the agents that get <agent>_<suffix> "
                                          "endpoints: 'auto' (all but the objects without a controller), 'all', "
                                          "or agent names, kinds, tag:NAME")
    standard: bool = Field(default=True, description="create the idiomatic topics (/clock, /tf, cmd_vel, ...)")
    qos: QosField = Field(default_factory=dict, description="per-topic QoS overrides, 'TOPIC: WORDS; ...'")

    @field_validator("sim_prefix")
    @classmethod
    def _prefix(cls, value: str) -> str:
        value = value.rstrip("/")
        if value and not re.fullmatch(r"(/[A-Za-z_][A-Za-z0-9_]*)+", value):
            raise ValueError(f"'{value}' is not a ROS namespace; valid: empty (root) or e.g. '/sim'")
        return value


class Ros2Feature(Feature):
    """``<plugin name="ros2" .../>``: holds the transport's settings for this world (does nothing per step)."""

    name = "ros2"
    config_model = Ros2Config

    def __init__(self, sim: Simulation, config: Ros2Config) -> None:
        unknown = sigros_agents(sim.world, config.sigros_agents)[1]
        if unknown:
            raise FieldError("sigros_agents", unknown)
        self.config = config


def automatic(model: AgentModel) -> bool:
    """Whether ``auto`` selects the agent ``model``: every robot, human and bodiless ``<agent>``, and an object
    only when it has a ``controller`` (sig_ros gave endpoints only to agents with a controller; a plain object,
    a box or a can, is reached through the shared ``/sigcore/sigros/<function>`` endpoints)."""
    return model.kind != "object" or model.controller is not None


def sigros_agents(world: World, words: tuple[str, ...]) -> tuple[set[str], str | None]:
    """The agents of ``world`` that ``words`` (``sigros_agents``) selects, and why a word selects nothing (it
    names no agent, kind or tag of the world; with the valid ones), or None."""
    if words == ("all",):
        return {a.name for a in world.agents}, None
    names = {a.name: a for a in world.agents}
    tags = sorted({t for a in world.agents if not isinstance(a, BareAgent) for t in a.tags})
    selected: set[str] = set()
    for word in words:
        if word == "auto":
            selected |= {a.name for a in world.agents if automatic(a)}
        elif word in AGENT_KINDS:
            selected |= {a.name for a in world.agents if a.kind == AGENT_KINDS[word]}
        elif word.startswith("tag:"):
            tag = word[4:]
            if tag not in tags:
                return selected, (f"no agent has the tag '{tag}'; tags of this world: {', '.join(tags) or 'none'}")
            selected |= {a.name for a in world.agents if not isinstance(a, BareAgent) and tag in a.tags}
        elif word in names:
            selected.add(word)
        else:
            few = ", ".join(list(names)[:6]) + (", ..." if len(names) > 6 else "")
            return selected, (f"'{word}' is no agent, kind or tag of this world; valid: auto, all, "
                              f"{', '.join(AGENT_KINDS)}, tag:NAME, or an agent name ({few})")
    return selected, None


def selects(world: World, words: tuple[str, ...], agent: str) -> bool:
    """Whether ``sigros_agents`` (``words``, checked when the world was loaded) selects ``agent`` of ``world``:
    for an agent added while running, by its name, kind, tags or controller (``auto``); a word naming an agent
    that is gone selects nothing."""
    model = next((a for a in world.agents if a.name == agent), None)
    return model is not None and selects_model(words, model)


def selects_model(words: tuple[str, ...], model: AgentModel) -> bool:
    """Whether ``sigros_agents`` (``words``) selects the agent ``model`` (:func:`selects`, given the model)."""
    tags = () if isinstance(model, BareAgent) else model.tags
    return any(word == "all" or word == model.name or AGENT_KINDS.get(word) == model.kind
               or (word == "auto" and automatic(model))
               or (word.startswith("tag:") and word[4:] in tags) for word in words)


def config_for(sim: Simulation) -> Ros2Config:
    """The world's ROS 2 settings: its ``<plugin name="ros2">`` element validated against :class:`Ros2Config`
    (defaults if it has none).

    Raises:
        sigcore.world.WorldError: an attribute is invalid (located in the world file).
    """
    element = sim.world.plugin(Ros2Feature.name)
    return Ros2Config() if element is None else validate_plugin(sim.world, element, Ros2Config)
