"""Messages as YAML text and YAML text as field values: how ``sigcore ros echo`` and ``call`` print a message or a
field of it (abbreviated like ``ros2 topic echo``), and how ``call`` reads its request's mapping."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import yaml

from sigcore.text import quote

from ..exceptions import RosToolError
from .messages import is_message, message_fields

TRUNCATE_LENGTH = 128
"""Default of ``echo --truncate-length``: longer arrays, sequences, strings and byte strings are cut there (``...``
marks the cut), like ``ros2 topic echo``'s default."""


@dataclass
class YamlStyle:
    """How :func:`to_plain` abbreviates: ``truncate`` (0: never), ``no_arr`` and ``no_str`` like ``ros2 topic echo``'s
    ``--truncate-length``, ``--no-arr`` and ``--no-str``."""

    truncate: int = TRUNCATE_LENGTH
    no_arr: bool = False
    no_str: bool = False


def to_plain(value: Any, style: YamlStyle | None = None) -> Any:
    """A ROS message (or field value) as plain Python data for YAML: fields in message order, nested messages as
    mappings, arrays as lists, longer ones cut at ``style.truncate`` with a last item ``'...'``."""
    style = style or YamlStyle()
    if is_message(value):
        out: dict[str, Any] = {}
        for name, ftype in message_fields(value).items():
            v = getattr(value, name)
            if style.no_arr and ("[" in ftype or ftype.startswith("sequence<")):
                out[name] = f"<{ftype}, length: {len(v)}>"
            elif style.no_str and ftype.startswith(("string", "wstring")):
                out[name] = f"<{ftype}, length: {len(v)}>"
            else:
                out[name] = to_plain(v, style)
        return out
    if isinstance(value, str):
        return value[:style.truncate] + "..." if style.truncate and len(value) > style.truncate else value
    if isinstance(value, bytes | bytearray):
        if len(value) == 1:  # a `byte` field
            return value[0]
        value = list(value)
    if hasattr(value, "tolist") and not isinstance(value, list):  # numpy arrays and scalars, array.array
        value = value.tolist()
    if isinstance(value, list | tuple):
        items = list(value)
        cut = bool(style.truncate) and len(items) > style.truncate
        plain = [to_plain(v, style) for v in (items[:style.truncate] if cut else items)]
        return [*plain, "..."] if cut else plain
    return value


def to_yaml(value: Any, style: YamlStyle | None = None) -> str:
    """``value`` (a message or a field's value) as YAML text like ``ros2 topic echo`` prints it, ending in a
    newline."""
    plain = to_plain(value, style)
    text = yaml.safe_dump(plain, sort_keys=False, default_flow_style=False, allow_unicode=True, width=1_000_000)
    if not isinstance(plain, dict | list) and text.endswith("\n...\n"):
        text = text[:-4]
    return text


def field_of(msg: Any, path: list[str], typename: str) -> Any:
    """``msg.a.b`` for ``path`` ``['a', 'b']``.

    Raises:
        RosToolError: a name that is not a field (naming the fields there are).
    """
    value = msg
    for i, name in enumerate(path):
        where = ".".join(path[:i]) or typename
        if not is_message(value):
            raise RosToolError(f"--field {'.'.join(path)}: {where} is not a message, it has no field {name!r}")
        fields = message_fields(value)
        if name not in fields:
            raise RosToolError(f"--field {'.'.join(path)}: {where} has no field {name!r}; its fields: "
                               f"{', '.join(fields) or 'none'}")
        value = getattr(value, name)
    return value


def parse_request(text: str) -> dict[str, Any]:
    """The YAML mapping of a request (empty text: no field set).

    Raises:
        RosToolError: malformed YAML (its error and where) or not a mapping.
    """
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise RosToolError(f"the request is not valid YAML: {problem}{where}: {quote(text)}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise RosToolError(f"the request must be a YAML mapping of fields, e.g. '{{data: true}}', not "
                           f"{quote(text)}")
    return data
