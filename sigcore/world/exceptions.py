"""Errors raised while reading a world file."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import SigcoreError


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
