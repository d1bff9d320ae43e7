"""Conversions between the API table's pydantic types, sigcore values and ROS 2 messages."""

from __future__ import annotations

import array
import importlib
import math
from typing import Any

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import TransformStamped
from pydantic import BaseModel

from sigcore.api.table import ApiEntry


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
        package, sub, name = entry.ros_type.split("/")
        return getattr(importlib.import_module(f"{package}.{sub}"), name)
    return getattr(importlib.import_module(f"sigcore_msgs.{kind}"), entry.ros_type)


def to_dict(msg: Any, model: type[BaseModel]) -> dict[str, Any]:
    """Fields of a received ROS message named like ``model``'s fields (sequences become lists)."""
    out: dict[str, Any] = {}
    for name in model.model_fields:
        value = getattr(msg, name)
        out[name] = list(value) if isinstance(value, array.array | list | tuple | np.ndarray) else value
    return out


def fill(msg: Any, fields: dict[str, Any]) -> Any:
    """Set ``msg``'s fields from ``fields`` (only those the message has); returns ``msg``."""
    slots = msg.get_fields_and_field_types()
    for name, value in fields.items():
        if name not in slots:
            continue
        kind = slots[name]
        if kind == "double":
            value = float(value)
        elif kind.startswith("sequence<double"):
            value = [float(v) for v in value]
        elif kind.startswith("sequence<string"):
            value = [str(v) for v in value]
        elif kind.startswith("int"):
            value = int(value)
        setattr(msg, name, value)
    return msg


def finite(*values: float) -> bool:
    """Whether every value is a finite number."""
    return all(math.isfinite(v) for v in values)


def ranges_array(ranges: np.ndarray) -> array.array:
    """A float32 ``array('f')`` of scan ranges (what LaserScan accepts without a per-element check)."""
    out = array.array("f")
    out.frombytes(np.ascontiguousarray(ranges, dtype=np.float32).tobytes())
    return out


def transform(parent: str, child: str, t: Time, xyz: Any, wxyz: Any) -> TransformStamped:
    """A ``TransformStamped`` ``parent -> child`` at time ``t``: translation [m], rotation (w, x, y, z)."""
    tf = TransformStamped()
    tf.header.stamp, tf.header.frame_id, tf.child_frame_id = t, parent, child
    tr, rot = tf.transform.translation, tf.transform.rotation
    tr.x, tr.y, tr.z = float(xyz[0]), float(xyz[1]), float(xyz[2])
    rot.w, rot.x, rot.y, rot.z = float(wxyz[0]), float(wxyz[1]), float(wxyz[2]), float(wxyz[3])
    return tf
