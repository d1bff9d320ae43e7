"""A ``<plugin ...>`` element's attributes validated against its feature's config model, with located errors.

Every problem comes out as a :class:`~sigcore.world.exceptions.WorldIssue` at the offending attribute's
``file:line:column`` (an unknown attribute lists the valid ones; a missing one points at the element), in the same
words as the rest of the world file (:mod:`sigcore.world.messages`).
"""

from __future__ import annotations

from typing import TypeVar

import annotated_types
from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from .exceptions import WorldError, WorldIssue
from .messages import error_field, message, unknown, value_range
from .models import PluginConfig, World

M = TypeVar("M", bound=BaseModel)

_BOUNDS = (annotated_types.Gt, annotated_types.Ge, annotated_types.Lt, annotated_types.Le)

_PARSING = {"float_parsing": "a number", "float_type": "a number", "int_parsing": "an integer",
            "int_type": "an integer", "int_from_float": "an integer"}


def plugin_issue(world: World, plugin: PluginConfig, attribute: str | None, text: str) -> WorldIssue:
    """A problem of ``plugin``, located at ``attribute`` (at the ``<plugin>`` element if ``None`` or absent)."""
    line, column = plugin.location(attribute)
    present = attribute if attribute in plugin.positions else None
    return WorldIssue(world.source, line, column, "plugin", present, text)


def validate_plugin(world: World, plugin: PluginConfig, model: type[M]) -> M:
    """``plugin``'s attributes (all but ``name``) as an instance of ``model``.

    Args:
        world: The world the element is in (for the file name in messages).
        plugin: The parsed ``<plugin>`` element.
        model: The feature's ``config_model``.

    Raises:
        WorldError: every problem, each at its attribute's ``file:line:column``: an unknown attribute (with the
            valid ones), a value that does not parse or is out of range (with what is valid), a missing required
            attribute (at the element), a cross-field rule.
    """
    fields = list(model.model_fields)
    issues = [plugin_issue(world, plugin, key, unknown(f"attribute of plugin '{plugin.name}'", key,
                                                        ["name", *fields]))
              for key in plugin.config if key not in fields]
    data = {k: v for k, v in plugin.config.items() if k in fields}
    try:
        config = model.model_validate(data)
    except ValidationError as e:
        for err in e.errors():
            field = error_field(err)
            attribute = field if field in plugin.config else None
            issue = plugin_issue(world, plugin, attribute, _message(model, err, data.get(field or "")))
            if issue not in issues:  # one per attribute and message ('inf inf' is two errors of one attribute)
                issues.append(issue)
        raise WorldError(_sorted(issues)) from None
    if issues:
        raise WorldError(_sorted(issues))
    return config


def _message(model: type[BaseModel], err: ErrorDetails, raw: str | None) -> str:
    """The world file's message for ``err``, plus what is valid when a value does not parse as a number."""
    text = message(model, err, raw)
    field = str(err["loc"][0]) if err["loc"] else ""
    info = model.model_fields.get(field)
    if err["type"] in _PARSING and info is not None:
        bounded = any(isinstance(m, _BOUNDS) for m in info.metadata)
        unit = value_range("", [], info.description).strip()  # "[s]", or "" without a unit
        valid = f", {value_range(field, info.metadata, info.description)}" if bounded else f" {unit}".rstrip()
        text += f"; valid: {_PARSING[err['type']]}{valid}"
    return text


def _sorted(issues: list[WorldIssue]) -> list[WorldIssue]:
    return sorted(issues, key=lambda i: (i.line, i.column))
