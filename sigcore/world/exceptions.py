"""Errors raised while reading a world file."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from ..errors import ApiError, SigcoreError

IssueCode = Literal["MISSING_ASSETS", "UNSUPPORTED_ASSETS", "UNSUPPORTED_ELEMENTS", "RESOURCE_PARSE_ERROR"]
"""simulation_interfaces' codes for a resource whose world-format text has issues (:func:`issue_code`)."""


@dataclass(frozen=True)
class WorldIssue:
    """One problem found in a world file.

    Attributes:
        file: The world file (or a referenced model file) the problem is in.
        line: 1-based line number.
        column: 1-based column number.
        element: The XML element the problem is on, e.g. ``object``.
        attribute: The attribute, or ``None`` when the element itself is wrong.
        message: What is wrong and what would be valid.
    """

    file: Path
    line: int
    column: int
    element: str | None
    attribute: str | None
    message: str

    @property
    def where(self) -> str:
        """``file:line:column``."""
        return f"{self.file}:{self.line}:{self.column}"

    def __str__(self) -> str:
        what = ""
        if self.element is not None:
            what = f"<{self.element}>"
            if self.attribute is not None:
                what += f" attribute '{self.attribute}'"
            what += ": "
        return f"{self.where}: {what}{self.message}"


class WorldError(SigcoreError, ValueError):
    """A world file is invalid; carries every problem found, each with its location."""

    def __init__(self, issues: list[WorldIssue]) -> None:
        self.issues = issues
        super().__init__("\n".join(str(i) for i in issues))


class FieldError(SigcoreError, ValueError):
    """Raised by a cross-field validator of a model to blame one field (the parser points at that attribute).

    Attributes:
        field: The field (XML attribute) that is wrong.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        super().__init__(message)


def issue_code(issues: Sequence[WorldIssue]) -> IssueCode:
    """The simulation_interfaces code for a world or element with ``issues``: MISSING_ASSETS (a file it names does
    not exist), UNSUPPORTED_ASSETS (a mesh sigcore cannot read), UNSUPPORTED_ELEMENTS (an element the format does
    not have), else RESOURCE_PARSE_ERROR."""
    messages = [i.message for i in issues]
    if any("file not found" in m for m in messages):
        return "MISSING_ASSETS"
    if any(m.startswith("mesh file") for m in messages):
        return "UNSUPPORTED_ASSETS"
    if any(m.startswith("unknown element") for m in messages):
        return "UNSUPPORTED_ELEMENTS"
    return "RESOURCE_PARSE_ERROR"


class RandomizeError(WorldError):
    """A world's ``<randomize>`` cannot be drawn with a seed: an entity found no free place in its attempts (the
    issue is at its ``<pose>``, naming the place, the attempts and what to change)."""


class SeedError(SigcoreError, ValueError):
    """A seed that is not an integer >= 0."""


class SpawnableError(WorldError):
    """A spawnable's element does not validate (the issues say where, in its ``spawnable.xml``)."""


class UrdfError(SigcoreError, ValueError):
    """A URDF file could not be read; ``line`` is its line (0 when unknown)."""

    def __init__(self, path: Path, line: int, message: str) -> None:
        self.path, self.line = path, line
        super().__init__(f"{path}:{line}: {message}")


RefusalCode = Literal["NAME_NOT_UNIQUE", "NAME_INVALID", "UNSUPPORTED_FORMAT", "NO_RESOURCE", "NAMESPACE_INVALID",
                      "RESOURCE_PARSE_ERROR", "MISSING_ASSETS", "UNSUPPORTED_ASSETS", "INVALID_POSE",
                      "NOT_FOUND", "OPERATION_FAILED", "UNSUPPORTED_ELEMENTS", "NO_WORLD_LOADED"]
"""Why a spawn or delete was refused: simulation_interfaces' ``SpawnResult`` codes, plus ``NOT_FOUND`` (no such
entity to delete) and ``OPERATION_FAILED`` (the backend failed); and for worlds (``catalogue``)
LoadWorld's ``UNSUPPORTED_ELEMENTS`` and UnloadWorld's ``NO_WORLD_LOADED``."""


class Refusal(ApiError):
    """A request refused because of what was asked, with simulation_interfaces' reason; nothing changed.

    Attributes:
        code: The reason (:data:`RefusalCode`), mapped to the standard result code by transports.
    """

    def __init__(self, code: RefusalCode, message: str) -> None:
        super().__init__(message)
        self.code: RefusalCode = code


class SpawnRefusal(Refusal):
    """A spawn or delete refused because of what was asked; nothing changed in the world."""


class WorldRefusal(Refusal):
    """A world request refused; the code is one of ``NO_RESOURCE``, ``UNSUPPORTED_FORMAT``, ``RESOURCE_PARSE_ERROR``,
    ``MISSING_ASSETS``, ``UNSUPPORTED_ASSETS``, ``UNSUPPORTED_ELEMENTS``, ``NOT_FOUND``, ``NO_WORLD_LOADED``,
    ``OPERATION_FAILED`` (simulation_interfaces' LoadWorld, UnloadWorld and GetCurrentWorld codes)."""
