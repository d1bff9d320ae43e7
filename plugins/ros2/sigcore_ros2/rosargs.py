"""``sigcore run WORLD ... --ros-args ARGS``: the ROS 2 command-line arguments the transport takes.

``-r FROM:=TO`` (``--remap``) and ``--log-level LEVEL`` go to rcl, as ``ros2 run`` would pass them, so remapping
and namespaces (``-r __ns:=/NS``, ``-r __node:=NAME``) apply to every endpoint of the transport's nodes, with ROS
2's rules (an absolute name is not moved by a namespace). ``-p NAME:=VALUE`` (``--param``) sets a field of
:class:`~sigcore_ros2.config.Ros2Config`, overriding the world file's ``<plugin name="ros2">``; ``use_sim_time`` may
be given as true only (the simulation is the clock). ``--log-level`` also sets the level of Python's ``sigcore``
loggers.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

from pydantic import ValidationError

from sigcore.errors import TransportError
from sigcore.world.messages import error_field
from sigcore.world.plugin_config import _message as attribute_message  # the world file's wording, "valid: ..."

from .config import Ros2Config

LOG_LEVELS = {"debug": logging.DEBUG, "info": logging.INFO, "warn": logging.WARNING, "warning": logging.WARNING,
              "error": logging.ERROR, "fatal": logging.CRITICAL}
"""rcl's log levels (case-insensitive) and the Python level each sets."""

VALID = "-r/--remap FROM:=TO, -p/--param NAME:=VALUE, --log-level LEVEL"
"""What ``--ros-args`` takes, for messages."""


@dataclass
class RosArgs:
    """The parsed ``--ros-args``.

    Attributes:
        rcl: What goes to ``rclpy.init`` (``--ros-args`` first): the remappings and log levels.
        params: ``-p`` settings by :class:`Ros2Config` field name, as given (validated).
        node_name: ``-r __node:=NAME`` (None: the default ``sigcore``).
        log_level: The Python level of ``--log-level LEVEL`` (None: unchanged).
    """

    rcl: list[str] = field(default_factory=list)
    params: dict[str, str] = field(default_factory=dict)
    node_name: str | None = None
    log_level: int | None = None


def parse_ros_args(args: list[str]) -> RosArgs:
    """Parse and check ``args`` (the tokens after ``--ros-args``).

    Raises:
        TransportError: an unknown argument, a malformed remapping, an unknown or invalid parameter, an unknown log
            level; each names what was wrong and what is valid.
    """
    from rclpy.exceptions import InvalidNamespaceException, InvalidNodeNameException, InvalidTopicNameException
    from rclpy.validate_namespace import validate_namespace
    from rclpy.validate_node_name import validate_node_name
    from rclpy.validate_topic_name import validate_topic_name

    out = RosArgs(rcl=["--ros-args"])
    tokens = iter(args)
    for token in tokens:
        if token == "--ros-args":  # rcl allows several sections
            continue
        if token not in ("-r", "--remap", "-p", "--param", "--log-level"):
            raise TransportError(f"unknown argument '{token}'; valid: {VALID}")
        value = next(tokens, None)
        if value is None:
            raise TransportError(f"'{token}' needs a value; valid: {VALID}")
        if token in ("-r", "--remap"):
            src, sep, dst = value.partition(":=")
            if not sep or not src or not dst:
                raise TransportError(f"-r '{value}' is not FROM:=TO; valid: e.g. -r /clock:=/sim/clock, "
                                     "-r __ns:=/sim, -r __node:=sim")
            try:
                if src == "__ns":
                    validate_namespace(dst)
                elif src == "__node":
                    validate_node_name(dst)
                    out.node_name = dst
                    continue
                else:
                    validate_topic_name(src.split(":", 1)[-1])
                    validate_topic_name(dst)
            except (InvalidNamespaceException, InvalidNodeNameException, InvalidTopicNameException) as e:
                raise TransportError(f"-r '{value}': {str(e).splitlines()[0]}") from None
            out.rcl += ["-r", value]
        elif token in ("-p", "--param"):
            name, sep, raw = value.partition(":=")
            if not sep or not name:
                raise TransportError(f"-p '{value}' is not NAME:=VALUE; valid: e.g. -p state_rate:=20")
            out.params[name] = _unquote(raw)
        else:
            logger, sep, level = value.rpartition(":=")
            if level.lower() not in LOG_LEVELS:
                raise TransportError(f"--log-level '{value}': unknown level '{level}'; valid: debug, info, warn, "
                                     "error, fatal")
            if not sep or logger == "sigcore" or logger.startswith("sigcore."):
                out.log_level = LOG_LEVELS[level.lower()]
            out.rcl += ["--log-level", value]
    check_params(out.params)
    return out


def _unquote(text: str) -> str:
    """``text`` without one pair of matching quotes around it (``"robots agents"`` -> ``robots agents``)."""
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    return text


def check_params(params: dict[str, str]) -> None:
    """Refuse a parameter that is not a :class:`Ros2Config` field (or ``use_sim_time:=true``), or whose value is
    invalid, as the world file's attribute would be.

    Raises:
        TransportError: naming the parameter and the valid ones, or what is valid for its value.
    """
    fields = list(Ros2Config.model_fields)
    for name, value in params.items():
        if name == "use_sim_time":
            if value.lower() != "true":
                raise TransportError(f"-p use_sim_time:={value}: use_sim_time is always true on sigcore's node (it "
                                     "is the source of simulated time); valid: true")
        elif name not in fields:
            raise TransportError(f"-p {name}: unknown parameter; valid: {', '.join(fields)}, use_sim_time "
                                 "(the attributes of <plugin name=\"ros2\">, docs/ros2.md)")
    settings = {k: v for k, v in params.items() if k != "use_sim_time"}
    validate_settings(settings, Ros2Config())


def validate_settings(params: dict[str, Any], base: Ros2Config) -> Ros2Config:
    """``base`` with ``params`` (field name -> value as text) applied and validated.

    Raises:
        TransportError: a value is invalid (naming the parameter and what is valid).
    """
    data = {**base.model_dump(), **params}
    try:
        return Ros2Config.model_validate(data)
    except ValidationError as e:
        first = e.errors()[0]
        name = error_field(first) or "?"
        raw = params.get(name)
        text = attribute_message(Ros2Config, first, raw if isinstance(raw, str) else None)
        raise TransportError(f"-p {name}:={raw}: {text}") from None
