"""Conversions between the API table's pydantic types, sigcore values and ROS 2 messages."""

from __future__ import annotations

import array
import math
from typing import Any

import numpy as np
from builtin_interfaces.msg import Time
from pydantic import BaseModel

from sigcore.api.table import ApiEntry
from sigcore.publish import Offered

from .cli.messages import message_class
from .publications import fill_message


def stamp(step_count: int, dt_ns: int) -> Time:
    """The ROS time of step ``step_count`` (exact: integer nanoseconds)."""
    ns = step_count * dt_ns
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def ros_type(entry: ApiEntry, kind: str) -> Any:
    """The ROS 2 class of an API entry: ``sigcore_msgs.msg.X`` / ``sigcore_msgs.srv.X`` or a full name such as
    ``sensor_msgs/msg/LaserScan``.

    Args:
        entry: The API entry.
        kind: ``msg`` or ``srv``.
    """
    if "/" in entry.ros_type:
        return message_class(entry.ros_type)
    return message_class(f"sigcore_msgs/{kind}/{entry.ros_type}")


def to_dict(msg: Any, model: type[BaseModel]) -> dict[str, Any]:
    """Fields of a received ROS message named like ``model``'s fields (sequences become lists)."""
    out: dict[str, Any] = {}
    for name in model.model_fields:
        value = getattr(msg, name)
        out[name] = list(value) if isinstance(value, array.array | list | tuple | np.ndarray) else value
    return out


def fill(msg: Any, fields: dict[str, Any]) -> Any:
    """Set ``msg``'s fields from ``fields`` (only those the message has; see :func:`fill_message`); returns
    ``msg``."""
    slots = msg.get_fields_and_field_types()
    return fill_message(msg, {name: value for name, value in fields.items() if name in slots})


def finite(*values: float) -> bool:
    """Whether every value is a finite number."""
    return all(math.isfinite(v) for v in values)


_OFFERED: dict[int, tuple[Any, tuple[str, str, Offered]]] = {}


def offered(pub: Any) -> tuple[str, str, Offered]:
    """``(full topic name, type name, offered QoS)`` of an rclpy publisher, as a recorder keeps them (cached per
    publisher: the cache holds the publisher, so its id is not reused while cached)."""
    hit = _OFFERED.get(id(pub))
    if hit is None or hit[0] is not pub:
        from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

        cls, qos = pub.msg_type, pub.qos_profile
        package = cls.__module__.split(".")[0]
        hit = _OFFERED[id(pub)] = (pub, (pub.topic_name, f"{package}/msg/{cls.__name__}",
                                         Offered(qos.depth, qos.reliability == ReliabilityPolicy.RELIABLE,
                                                 qos.durability == DurabilityPolicy.TRANSIENT_LOCAL)))
    return hit[1]
