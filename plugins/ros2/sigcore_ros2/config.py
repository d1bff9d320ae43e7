"""Configuration of the ROS 2 transport: ``<plugin name="ros2" .../>`` in the world file (all optional).

Example::

    <plugin name="ros2" clock_rate="0" state_rate="50" sim_prefix="" sigros="true" standard="true"
            qos="/clock: best_effort; /robot_000/base_scan: best_effort depth=1"/>

The ``ros2`` feature only stores this configuration; the transport reads it when it starts.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from sigcore.feature import Feature

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

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
            raise ValueError(f"qos: '{item}' is not 'TOPIC: WORDS' (e.g. '/clock: best_effort depth=1')")
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
                raise ValueError(f"qos: unknown word '{word}' for {topic}; valid: {', '.join(QOS_WORDS)}, depth=N")
        out[topic if topic.startswith("/") else "/" + topic] = QosOverride(**fields)  # type: ignore[arg-type]
    return out


class Ros2Config(BaseModel):
    """Settings of the ROS 2 transport.

    Attributes:
        clock_rate: /clock publication rate [Hz]; 0 publishes every step (the default).
        state_rate: Rate of /tf, odom and joint_states [Hz].
        sim_prefix: Prefix of the simulation_interfaces services and action (e.g. ``/sim``; default: root).
        sigros: Create the sig_ros-compatible ``<agent>_<suffix>`` endpoints.
        standard: Create the idiomatic topics (/clock, /tf, cmd_vel, odom, joint_states, scans).
        qos: Per-topic QoS overrides, by absolute topic name.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    clock_rate: float = Field(default=0.0, ge=0.0)
    state_rate: float = Field(default=50.0, gt=0.0)
    sim_prefix: str = ""
    sigros: bool = True
    standard: bool = True
    qos: dict[str, QosOverride] = Field(default_factory=dict)

    @field_validator("sim_prefix")
    @classmethod
    def _prefix(cls, value: str) -> str:
        value = value.rstrip("/")
        if value and not re.fullmatch(r"(/[A-Za-z_][A-Za-z0-9_]*)+", value):
            raise ValueError(f"sim_prefix '{value}' is not a ROS namespace such as '/sim'")
        return value

    @classmethod
    def from_attributes(cls, attrs: dict[str, str]) -> Ros2Config:
        """Build from the ``<plugin name="ros2">`` attributes (strings).

        Raises:
            ValueError: an unknown attribute or a bad value, naming it and what is valid.
        """
        data: dict[str, object] = dict(attrs)
        unknown = sorted(set(data) - set(cls.model_fields))
        if unknown:
            raise ValueError(f"unknown attribute(s) {', '.join(unknown)}; valid: {', '.join(cls.model_fields)}")
        if "qos" in data:
            data["qos"] = parse_qos(str(data["qos"]))
        try:
            return cls.model_validate(data)
        except ValidationError as e:
            problems = "; ".join(f"{'.'.join(map(str, err['loc']))}: {err['msg']}" for err in e.errors())
            raise ValueError(problems) from None


class Ros2Feature(Feature):
    """``<plugin name="ros2" .../>``: holds the transport's settings for this world (does nothing per step)."""

    name = "ros2"

    def __init__(self, sim: Simulation, config: dict[str, str]) -> None:
        self.config = Ros2Config.from_attributes(config)


def config_for(sim: Simulation) -> Ros2Config:
    """The world's ROS 2 settings (defaults if it has no ``<plugin name="ros2">``)."""
    feature = sim.features.get("ros2")
    return feature.config if isinstance(feature, Ros2Feature) else Ros2Config()
