"""The sig_ros message format Referee/<text>/<points>, read strictly, and the recorded events."""

from __future__ import annotations

import json

import pytest
from sigcore_referee.events import RefereeEvent, RefereeMessage, parse_message
from sigcore_referee.exceptions import MESSAGE_FORMAT, MessageFormatError


@pytest.mark.parametrize(("text", "expected"), [
    ("Referee/collision with the wall/-100", RefereeMessage("collision with the wall", -100)),
    ("Referee/good job/+50", RefereeMessage("good job", 50)),
    ("Referee/ spaces around / 7 ", RefereeMessage("spaces around", 7)),
    ("Referee/a/b/3", RefereeMessage("a/b", 3)),
])
def test_valid_messages(text: str, expected: RefereeMessage) -> None:
    """Text is everything between the first and the last slash; points are a signed integer."""
    assert parse_message(text) == expected


@pytest.mark.parametrize(("text", "reason"), [
    ("", "must start with 'Referee/'"),
    ("hello", "must start with 'Referee/'"),
    ("referee/x/5", "must start with 'Referee/'"),
    ("Referee", "must start with 'Referee/'"),
    ("Referee/x", "no '/<points>' at the end"),
    ("Referee//5", "text between the slashes is empty"),
    ("Referee/x/1.5", "points '1.5' are not an integer"),
    ("Referee/x/abc", "points 'abc' are not an integer"),
    ("Referee/x/", "points '' are not an integer"),
    ("Referee/x/99999999", "beyond"),
    (42, "expected a string, got int"),
])
def test_malformed_messages_say_why_and_the_format(text: object, reason: str) -> None:
    """Every malformed text raises MessageFormatError giving the reason and the expected format."""
    with pytest.raises(MessageFormatError) as info:
        parse_message(text)
    assert reason in str(info.value) and MESSAGE_FORMAT in str(info.value)


def test_event_serialisations() -> None:
    """An event gives JSON with its four fields and the sig_ros message form."""
    e = RefereeEvent(12.5, "grasp", "robot_000 grasped can_0", 50)
    assert json.loads(e.to_json()) == {"time": 12.5, "kind": "grasp", "text": "robot_000 grasped can_0",
                                       "points": 50}
    assert parse_message(e.to_message()) == RefereeMessage("robot_000 grasped can_0", 50)
