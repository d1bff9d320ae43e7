"""Pydantic validation errors -> the world file's messages: what is wrong, then ``valid: ...``.

Ranges, choices and units are read from the models themselves (``Field(gt=..., description="... [s]")``,
``Literal[...]``), so a message can never disagree with the code.
"""

from __future__ import annotations

import difflib
import re
import typing
from typing import Any, Literal

import annotated_types
from pydantic import BaseModel
from pydantic_core import ErrorDetails

from .exceptions import FieldError

_NAME_HELP = "a letter, then letters, digits or '_' (names become ROS 2 topic names), e.g. 'robot_000'"
_UNIT = re.compile(r"\[([^\]]+)\]")


def error_field(err: ErrorDetails) -> str | None:
    """The field a validation error is about: its location, or the field a :class:`FieldError` blames."""
    cause = (err.get("ctx") or {}).get("error")
    if isinstance(cause, FieldError):
        return cause.field
    return str(err["loc"][0]) if err["loc"] else None


def message(model: type[BaseModel], err: ErrorDetails, raw: str | None) -> str:
    """One error of ``model`` as a world-file message; ``raw`` is the attribute's text, if it was given."""
    kind = err["type"]
    field = str(err["loc"][0]) if err["loc"] else None
    info = model.model_fields.get(field) if field else None
    if kind == "missing" and field is not None:
        hint = f" ({info.description})" if info is not None and info.description else ""
        return f"required attribute '{field}' is missing{hint}"
    if kind == "value_error":
        return str(err["ctx"]["error"]) if "ctx" in err else err["msg"].removeprefix("Value error, ")
    got = repr(raw) if raw is not None else repr(err["input"])
    if kind == "literal_error" and info is not None:
        return f"{got} is not valid; valid: {', '.join(literal_values(info.annotation))}"
    if kind in ("float_parsing", "float_type"):
        return f"{got} is not a number"
    if kind in ("int_parsing", "int_type", "int_from_float"):
        return f"{got} is not an integer"
    if kind == "finite_number":
        return f"{got} is not a finite number; NaN and infinity are not allowed"
    if kind in ("bool_parsing", "bool_type"):
        return f"{got} is not a boolean; valid: true, false"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal") and info is not None:
        return f"{got} is out of range; valid: {value_range(field or '', info.metadata, info.description)}"
    if kind == "string_pattern_mismatch":
        return f"invalid name {got}; valid: {_NAME_HELP}"
    if kind == "string_too_long":
        return f"{got} is too long; valid: at most {err.get('ctx', {}).get('max_length')} characters"
    return f"{err['msg']} (got {got})"


def literal_values(annotation: Any) -> list[str]:
    """The choices of a ``Literal`` annotation (also inside ``X | None``)."""
    if typing.get_origin(annotation) is Literal:
        return [str(v) for v in typing.get_args(annotation)]
    return [v for arg in typing.get_args(annotation) for v in literal_values(arg)]


def value_range(name: str, metadata: list[Any], description: str | None) -> str:
    """``"0 < timestep <= 0.1 [s]"`` or ``"kp > 0"``: a field's ``gt``/``ge``/``lt``/``le`` and unit."""
    low = high = ""
    for m in metadata:
        if isinstance(m, annotated_types.Gt):
            low = f"{m.gt:g} < "
        elif isinstance(m, annotated_types.Ge):
            low = f"{m.ge:g} <= "
        elif isinstance(m, annotated_types.Lt):
            high = f" < {m.lt:g}"
        elif isinstance(m, annotated_types.Le):
            high = f" <= {m.le:g}"
    if low and not high:  # one-sided: "kp > 0" reads better than "0 < kp"
        bound, op = low.split()
        text = f"{name} {'>' if op == '<' else '>='} {bound}"
    else:
        text = f"{low}{name}{high}"
    unit = _UNIT.search(description or "")
    return text + (f" [{unit.group(1)}]" if unit else "")


def unknown(what: str, name: str, valid: list[str]) -> str:
    """``unknown attribute (did you mean 'color'?); valid: ...``."""
    close = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    hint = f" (did you mean '{close[0]}'?)" if close else ""
    return f"unknown {what}{hint}; valid: {', '.join(valid)}"
