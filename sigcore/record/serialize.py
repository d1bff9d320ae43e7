"""Serializing publications to CDR without ROS 2: rosbags' typestore (ROS 2 Jazzy's standard types) plus the
``sigcore_msgs`` types of the declared publications, registered from their pydantic models.

Values are the publication contract's field dictionaries (:mod:`sigcore.publish`): nested dictionaries, sequences as
lists or numpy arrays, ``builtin_interfaces/Time`` as an int of nanoseconds or a float of seconds. A field a value
leaves out takes the type's default (0, false, empty), as a ROS message constructed without it does.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SigcoreError
from .exceptions import SerializeError

if TYPE_CHECKING:
    from pydantic import BaseModel

_NUMPY = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "int8": np.int8, "uint8": np.uint8,
          "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32, "int64": np.int64,
          "uint64": np.uint64, "float32": np.float32, "float64": np.float64}
_TIME = "builtin_interfaces/msg/Time"


class Serializer:
    """CDR bytes, message definitions and RIHS01 hashes of ROS 2 types, from Python values, without ROS 2."""

    def __init__(self) -> None:
        from rosbags.interfaces import Nodetype
        from rosbags.typesys import Stores, get_typestore

        self._store = get_typestore(Stores.ROS2_JAZZY)
        self._nodetype = Nodetype
        self._defs: dict[str, tuple[str, str]] = {}
        self._builders: dict[str, Callable[[Any], Any]] = {}

    def register(self, typename: str, model: type[BaseModel]) -> None:
        """Make the ``sigcore_msgs`` type ``typename`` (``sigcore_msgs/msg/X``) known from its pydantic model."""
        if typename in self._store.types:
            return
        from rosbags.typesys import get_types_from_msg

        from ..api.interfaces import message_definition

        self._store.register(get_types_from_msg(message_definition(model), typename))

    def register_types(self, types: dict[str, Any]) -> None:
        """Make types known from rosbags' parsed definitions (``rosbags.typesys.get_types_from_msg``), e.g. an
        interface package's ``.msg`` files."""
        self._store.register(types)

    def knows(self, typename: str) -> bool:
        """Whether ``typename`` (``pkg/msg/Name``) can be serialized."""
        return typename in self._store.types

    def definition(self, typename: str) -> tuple[str, str]:
        """``(message definition, RIHS01 hash)`` of ``typename``: the concatenated ``.msg`` text rosbag2 and MCAP
        keep (``ros2msg``) and the type hash ROS 2 Jazzy computes."""
        if typename not in self._defs:
            if not self.knows(typename):
                raise SerializeError(f"type {typename!r} is unknown to the recorder's type store (ROS 2 Jazzy's "
                                     "standard types and the sigcore_msgs of the declared publications)")
            text, _ = self._store.generate_msgdef(typename, ros_version=2)
            self._defs[typename] = (text, self._store.hash_rihs01(typename))
        return self._defs[typename]

    def serialize(self, typename: str, value: dict[str, Any]) -> bytes:
        """The CDR bytes (little endian, with the encapsulation header) of ``value``, a field dictionary of
        ``typename``.

        Raises:
            SerializeError: an unknown type, an unknown field or a value that does not fit its field.
        """
        try:
            message = self._builder(typename)(value)
            return bytes(self._store.serialize_cdr(message, typename))
        except _Misfit as e:
            raise SerializeError(f"{typename}{e.path}: {e.message}") from None
        except SerializeError:
            raise
        except Exception as e:  # rosbags' own errors on a value of the wrong type or size
            raise SerializeError(f"{typename}: {type(e).__name__}: {e}") from None

    def deserialize(self, typename: str, data: bytes) -> Any:
        """The message (a rosbags dataclass: fields as attributes) that CDR ``data`` of ``typename`` holds."""
        return self._store.deserialize_cdr(data, typename)

    # ------------------------------------------------------------------ dict -> rosbags message
    def _builder(self, typename: str) -> Callable[[Any], Any]:
        """The function that makes a rosbags message of ``typename`` from a field dictionary, made once per type
        (a value's fields are then converted without looking the type up again: a laser scan in about half the
        time).

        Raises:
            SerializeError: the type is unknown to the store.
        """
        built = self._builders.get(typename)
        if built is not None:
            return built
        try:
            cls = self._store.types[typename]
            _, fields = self._store.fielddefs[typename]
        except KeyError:
            raise SerializeError(f"type {typename!r} is unknown to the recorder's type store") from None
        converters: list[tuple[str, Callable[[Any], Any]]] = []
        names = frozenset(name for name, _ in fields)
        listed = ", ".join(name for name, _ in fields)

        def build(value: Any) -> Any:
            given = value if isinstance(value, dict) else dict(value or {})
            if not names.issuperset(given):
                extra = ", ".join(repr(k) for k in given if k not in names)
                raise _Misfit("", f"{typename} has no field {extra}; fields: {listed}")
            kwargs = {}
            for name, convert in converters:
                try:
                    kwargs[name] = convert(given.get(name))
                except _Misfit as e:
                    raise _Misfit(f".{name}{e.path}", e.message) from None
            return cls(**kwargs)

        if typename == _TIME:
            time_cls, plain = cls, build

            def build_time(value: Any) -> Any:
                if value is None or isinstance(value, dict):
                    return plain(value)
                ns = int(value) if isinstance(value, int | np.integer) else round(float(value) * 1e9)
                sec, nanosec = divmod(ns, 1_000_000_000)
                return time_cls(sec=sec, nanosec=nanosec)

            self._builders[typename] = build_time
        else:
            self._builders[typename] = build
        converters.extend((name, self._converter(desc)) for name, desc in fields)
        return self._builders[typename]

    def _converter(self, desc: tuple[Any, Any]) -> Callable[[Any], Any]:
        """The conversion of one field's value (None: the field's default)."""
        kind, spec = desc
        node = self._nodetype
        if kind == node.BASE:
            base = spec[0]
            if base == "string" or base == "wstring":
                return lambda v: "" if v is None else str(v)
            if base == "bool":
                return bool
            if base.startswith("float"):
                return lambda v: 0.0 if v is None else float(v)
            return lambda v: 0 if v is None else int(v)
        if kind == node.NAME:
            return self._builder(spec)
        inner, size = spec
        fixed = kind == node.ARRAY
        if inner[0] == node.BASE and inner[1][0] in _NUMPY:
            dtype = _NUMPY[inner[1][0]]

            def numbers(v: Any) -> Any:
                if v is None:
                    return np.zeros(size if fixed else 0, dtype=dtype)
                if isinstance(v, bytes | bytearray | memoryview) and dtype is np.uint8:
                    return np.frombuffer(bytes(v), dtype=np.uint8)
                return np.ascontiguousarray(v, dtype=dtype).reshape(-1)

            return numbers
        item = self._converter(inner)

        def items(v: Any) -> list[Any]:
            values = ([None] * size if fixed else []) if v is None else list(v)
            out = []
            for i, value in enumerate(values):
                try:
                    out.append(item(value))
                except _Misfit as e:
                    raise _Misfit(f"[{i}]{e.path}", e.message) from None
            return out

        return items


class _Misfit(SigcoreError):
    """A value that does not fit its type, found ``path`` (``.field[2].x``) below the message being built."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__(message)
        self.path = path
        self.message = message
