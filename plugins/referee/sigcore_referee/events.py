"""What the referee records: scored events, and the sig_ros message that reports one."""

from __future__ import annotations

import json
import re
from dataclasses import asdict, dataclass
from typing import Literal

from .exceptions import MessageFormatError

Kind = Literal["grasp", "correct_box", "wrong_box", "outside", "collision", "message", "end"]
"""``grasp``: first grasp of a trash item; ``correct_box`` / ``wrong_box``: an item came to rest in a trash box;
``outside``: a released or moved item came to rest outside every box (0 points); ``collision``: a robot's contact
episode with furniture, a wall or the floor; ``message``: a ``Referee/text/points`` message of the viewer service;
``end``: the task ended (0 points; the text says why)."""

MAX_POINTS = 1_000_000
"""Largest magnitude of the points of one message."""

_INTEGER = re.compile(r"[+-]?[0-9]+")


@dataclass(frozen=True, slots=True)
class RefereeEvent:
    """One entry of the referee's record.

    Attributes:
        time: Simulation time [s].
        kind: What happened (see :data:`Kind`).
        text: For people, e.g. ``"robot_000 put can_0 in trashbox_2"``.
        points: Points added to the score (negative for a penalty).
    """

    time: float
    kind: Kind
    text: str
    points: int

    def to_json(self) -> str:
        """The event as one JSON object (what a transport may publish as a ``std_msgs/String``)."""
        return json.dumps(asdict(self))

    def to_message(self) -> str:
        """The event in the sig_ros referee format ``Referee/<text>/<points>``."""
        return f"Referee/{self.text}/{self.points}"


@dataclass(frozen=True, slots=True)
class RefereeMessage:
    """A parsed ``Referee/<text>/<points>`` text.

    Attributes:
        text: Everything between the first and the last ``/``, stripped (may itself contain ``/``).
        points: The integer after the last ``/``.
    """

    text: str
    points: int


def parse_message(text: object) -> RefereeMessage:
    """Read a sig_ros referee message.

    Raises:
        MessageFormatError: not a string, not starting with ``Referee/``, no text, or points that are not an
            integer within ±:data:`MAX_POINTS`.
    """
    if not isinstance(text, str):
        raise MessageFormatError(repr(text), f"expected a string, got {type(text).__name__}")
    head, sep, rest = text.partition("/")
    if head.strip() != "Referee" or not sep:
        raise MessageFormatError(text, "it must start with 'Referee/'")
    body, sep, points = rest.rpartition("/")
    if not sep:
        raise MessageFormatError(text, "no '/<points>' at the end")
    if not body.strip():
        raise MessageFormatError(text, "the text between the slashes is empty")
    if not _INTEGER.fullmatch(points.strip()):
        raise MessageFormatError(text, f"points {points.strip()!r} are not an integer")
    value = int(points)
    if abs(value) > MAX_POINTS:
        raise MessageFormatError(text, f"points {value} are beyond ±{MAX_POINTS}")
    return RefereeMessage(body.strip(), value)
