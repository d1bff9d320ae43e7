"""ROS 2 interface classes and messages: the one place where a type name (``geometry_msgs/msg/Twist``,
``pkg/srv/Name``) becomes its Python class (:func:`message_class`, for the transport and the bag player too), and the
filling of a message from a YAML mapping with every field checked (``sigcore ros call``'s request)."""

from __future__ import annotations

import importlib
import re
import sys
from typing import Any

from sigcore.text import quote

from ..exceptions import RosToolError


def message_class(typename: str, kind: str = "msg") -> Any:
    """The Python class of the ROS 2 interface ``typename``: ``pkg/msg/Name``, ``pkg/srv/Name`` (any
    ``pkg/<sub>/Name``: imported from the ``pkg.<sub>`` module), or ``pkg/Name`` as nested field types are spelled
    (imported from ``pkg.<kind>``).

    Raises:
        ImportError: the package (or its module) is not installed; AttributeError: it has no such type.
    """
    parts = typename.split("/")
    package, name = parts[0], parts[-1]
    sub = parts[1] if len(parts) == 3 else kind
    return getattr(importlib.import_module(f"{package}.{sub}"), name)


def interface_class(typename: str, kind: str = "msg") -> Any:
    """The rclpy class of ``pkg/msg/Name`` (``kind`` ``msg``) or ``pkg/srv/Name`` (``srv``), through
    :func:`message_class`.

    Raises:
        RosToolError: not a type name, or its package is not installed (naming what to install).
    """
    parts = typename.split("/")
    if len(parts) != 3 or parts[1] != kind or not all(parts):
        raise RosToolError(f"{quote(typename)} is not a ROS 2 {kind} type name (package/{kind}/Name)")
    package, _, name = parts
    try:
        return message_class(typename, kind)
    except AttributeError:
        raise RosToolError(f"type {typename} cannot be imported: the installed package {package!r} has no {kind} "
                           f"{name!r} (not the version the publisher uses?)") from None
    except (ImportError, ValueError):
        raise RosToolError(
                f"type {typename} cannot be imported: its Python package {package!r} (generated interfaces) is not "
                f"in this environment ({sys.prefix}); install it (pip install ros-jazzy-{package.replace('_', '-')} "
                "where that wheel exists; sigcore's own interface packages: scripts/setup.sh) or source a ROS 2 "
                "workspace that has it") from None


def message_fields(msg: Any) -> dict[str, str]:
    """The fields of a message (or of its class) and their types, in message order."""
    fields: dict[str, str] = msg.get_fields_and_field_types()
    return fields


def is_message(value: Any) -> bool:
    """Whether ``value`` is a ROS message (not a field's plain value)."""
    return hasattr(value, "get_fields_and_field_types")


def _slot(msg: Any, name: str) -> Any:
    """The rosidl_parser type of field ``name`` of ``msg``."""
    return dict(zip(message_fields(msg), type(msg).SLOT_TYPES, strict=True))[name]


def _namespaced_class(t: Any) -> Any:
    """The class of a rosidl_parser ``NamespacedType`` (a nested message field's type)."""
    return message_class("/".join([*t.namespaces, t.name]))


def checked(cls: Any) -> Any:
    """A new message of ``cls`` whose field setters check types, ranges and lengths (rclpy skips those checks unless
    ``ROS_PYTHON_CHECK_FIELDS=1``, and serializes a wrong value into garbage)."""
    try:
        return cls(check_fields=True)
    except TypeError:  # a class generated before Jazzy: it always checks
        return cls()


def fill(msg: Any, values: Any, where: str) -> Any:
    """Set the fields of ``msg`` (a request, made by :func:`checked`) from ``values``, a mapping read from YAML:
    nested messages as mappings, sequences of messages as lists of mappings, integers where floats are expected.
    Returns ``msg``.

    Raises:
        RosToolError: an unknown field (naming the valid ones), a mapping where a value is expected or a value
            that does not fit its field (naming the field and its type).
    """
    from rosidl_parser.definition import AbstractNestedType, NamespacedType

    if not isinstance(values, dict):
        raise RosToolError(f"{where} is a message ({type(msg).__name__}): give a mapping of its fields, not "
                           f"{quote(values)}")
    fields = message_fields(msg)
    for key, value in values.items():
        here = f"{where}.{key}"
        if key not in fields:
            raise RosToolError(f"{where} has no field {quote(key)}; its fields: {', '.join(fields) or 'none'}")
        ftype, slot = fields[key], _slot(msg, key)
        if isinstance(slot, NamespacedType):
            value = fill(checked(_namespaced_class(slot)), value, here)
        elif isinstance(slot, AbstractNestedType) and isinstance(slot.value_type, NamespacedType):
            if not isinstance(value, list):
                raise RosToolError(f"{here} is {ftype}: give a list of mappings, not {quote(value)}")
            cls = _namespaced_class(slot.value_type)
            value = [fill(checked(cls), item, f"{here}[{i}]") for i, item in enumerate(value)]
        else:
            value = _coerce(ftype, value, here)
        try:
            setattr(msg, key, value)
        except (AssertionError, TypeError, ValueError, OverflowError) as e:
            detail = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise RosToolError(f"{here} is {ftype}: {quote(value)} does not fit ({detail})") from None
    return msg


_FLOATS = ("float", "double", "long double")


def _coerce(ftype: str, value: Any, where: str) -> Any:
    """A YAML value made the Python type rclpy expects for a field of ``ftype`` where that is lossless."""
    sequence = re.fullmatch(r"sequence<(.+?)(?:, \d+)?>", ftype) or re.fullmatch(r"(.+)\[\d+\]", ftype)
    base, nested = (sequence.group(1), True) if sequence else (ftype, False)

    def one(v: Any) -> Any:
        if isinstance(v, dict | list):
            raise RosToolError(f"{where} is {ftype}: {quote(v)} is not a {base}")
        if base in _FLOATS and isinstance(v, int) and not isinstance(v, bool):
            return float(v)
        if base == "octet" and isinstance(v, int) and not isinstance(v, bool) and 0 <= v < 256:
            return bytes([v])
        return v

    if nested:
        if not isinstance(value, list):
            raise RosToolError(f"{where} is {ftype}: give a list, not {quote(value)}")
        return [one(v) for v in value]
    return one(value)
