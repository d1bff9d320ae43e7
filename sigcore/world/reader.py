"""What reads one world file: :class:`Reader` keeps the issues found, each located at ``file:line:column``, and
turns an element's attributes into a model (:mod:`sigcore.world.parser` uses it for every element)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from lxml import etree
from pydantic import BaseModel, ValidationError

from .exceptions import WorldIssue
from .locate import SourceMap
from .messages import error_field, message, unknown
from .urdf import UrdfFiles

INTERNAL_FIELDS = {"kind", "lidars", "cameras", "grippers", "arms", "drive", "gains", "plugins", "agents", "source",
                   "config", "line", "column", "positions", "named_poses", "randomize", "poses", "choices",
                   "options", "attributes", "path", "waypoints"}
"""Model fields that are not attributes: children, locations, what the parser fills in."""


class Reader:
    """One world file being read: its source map (for locations), the issues found so far, where each agent is,
    and the URDF files read."""

    def __init__(self, path: Path, text: str, root: etree._Element) -> None:
        self.path = path
        self.map = SourceMap(text, root)
        self.issues: list[WorldIssue] = []
        self.locations: dict[tuple[str, str | None], tuple[int, int]] = {}
        self.urdfs = UrdfFiles()

    def issue(self, element: etree._Element, attribute: str | None, message: str) -> None:
        line, col = self.map.attribute(element, attribute) if attribute else self.map.element(element)
        self.issues.append(WorldIssue(self.path, line, col, str(element.tag), attribute, message))

    def line(self, element: etree._Element) -> int:
        return self.map.element(element)[0]

    def attributes(self, element: etree._Element, model: type[BaseModel]) -> dict[str, Any]:
        fields = sorted(set(model.model_fields) - INTERNAL_FIELDS)
        out: dict[str, Any] = {}
        for key, value in element.attrib.items():
            key = str(key)
            if key not in fields:
                self.issue(element, key, unknown("attribute", key, fields))
            else:
                out[key] = str(value)
        return out

    def build(self, element: etree._Element, model: type[BaseModel], extra: dict[str, Any]) -> Any:
        """``element``'s attributes and ``extra`` (fields from children) as a ``model``; None on error."""
        data = self.attributes(element, model)
        try:
            return model.model_validate({**data, **extra})
        except ValidationError as e:
            for err in e.errors():
                field = error_field(err)
                attribute = field if field in data else None
                self.issue(element, attribute, message(model, err, data.get(field) if field else None))
            return None

    def children_of(self, element: etree._Element, allowed: dict[str, Any]) -> list[etree._Element]:
        """The child elements of ``element`` whose tag is in ``allowed``; reports the others and any text."""
        out = []
        for child in element:
            if isinstance(child, etree._Entity):  # an entity reference left unexpanded: text, which has no place
                self.issues.append(WorldIssue(self.path, int(child.sourceline or self.line(element)), 1,
                                              str(element.tag), None, f"unexpected entity reference {child.text}; "
                                              f"<{element.tag}> holds no text and entities are not expanded"))
                continue
            if not isinstance(child.tag, str):
                continue  # comments, processing instructions
            if child.tag in allowed:
                out.append(child)
            elif allowed:
                what = f"element inside <{element.tag}>"
                self.issue(child, None, unknown(what, str(child.tag), list(allowed)))
            else:
                self.issue(child, None, f"unexpected element; <{element.tag}> has no child elements, only "
                                        "attributes")
        texts = [t.strip() for t in [element.text, *(c.tail for c in element)] if t and t.strip()]
        if texts:
            line, col = self.map.text(element)
            holds = "only elements" if allowed else "no text; write values as attributes"
            says = f"unexpected text {texts[0][:30]!r}; <{element.tag}> holds {holds}"
            self.issues.append(WorldIssue(self.path, line, col, str(element.tag), None, says))
        return out
