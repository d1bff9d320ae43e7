"""The plugin's attributes: defaults, and errors located at the attribute that name it and what is valid."""

from __future__ import annotations

from pathlib import Path

import pytest
from pydantic import ValidationError
from referee_worlds import BOXES, ITEMS, make_sim
from sigcore_referee.config import RefereeConfig

from sigcore.world import WorldError


def test_defaults_are_the_issue_points() -> None:
    """With no attributes: service only, +1000 / -600 / +50 / -100, 600 s limit, 0.5 s debounce."""
    c = RefereeConfig.model_validate({})
    assert (c.rules, c.service) == ("none", "referee")
    assert (c.correct_box, c.wrong_box, c.grasp, c.collision) == (1000, -600, 50, -100)
    assert (c.time_limit, c.debounce, c.rest_time) == (600.0, 0.5, 0.5)
    assert c.collision_tags == ("furniture", "wall") and c.floor and not c.stop_on_finish


def test_strings_are_converted() -> None:
    """Points, times, tag lists, corners and booleans are read from their attribute strings."""
    c = RefereeConfig.model_validate({"rules": "cleanup", "correct_box": "+500", "time_limit": "90.5",
                                       "collision_tags": "wall  furniture trashbox", "stop_on_finish": "true",
                                       "box_inner": "-0.1 -0.1 0 0.1 0.1 0.3", "floor_parts": "a b"})
    assert (c.correct_box, c.time_limit, c.stop_on_finish) == (500, 90.5, True)
    assert c.collision_tags == ("wall", "furniture", "trashbox") and c.floor_parts == ("a", "b")
    assert c.box_inner == (-0.1, -0.1, 0.0, 0.1, 0.1, 0.3)


def test_unknown_attribute_suggests_the_close_one(tmp_path: Path) -> None:
    """A misspelt attribute is refused at its column with the closest valid name and the list of valid ones."""
    with pytest.raises(WorldError) as info:
        make_sim(tmp_path, BOXES + ITEMS, 'corect_box="1000"')
    [issue] = info.value.issues
    assert (issue.line, issue.column, issue.attribute) == (2, 26, "corect_box")
    assert "(did you mean 'correct_box'?); valid: name, rules, service, correct_box" in issue.message


@pytest.mark.parametrize(("attr", "value", "valid"), [
    ("collision", "-1.5", "'-1.5' is not an integer; valid: an integer [points]"),
    ("grasp", "many", "'many' is not an integer; valid: an integer [points]"),
    ("rules", "robocup", "'robocup' is not valid; valid: cleanup, none"),
    ("time_limit", "-1", "'-1' is out of range; valid: time_limit >= 0 [s]"),
    ("box_inner", "0 0 0 1 1", "expected 6 numbers 'x0 y0 z0 x1 y1 z1', got 5"),
    ("stop_on_finish", "maybe", "'maybe' is not a boolean; valid: true, false"),
    ("service", "my service", "'my service' has spaces; valid: one word"),
])
def test_bad_value_names_attribute_and_valid_values(tmp_path: Path, attr: str, value: str, valid: str) -> None:
    """A bad value is refused at the attribute's line:column with the value given and what is valid."""
    with pytest.raises(WorldError) as info:
        make_sim(tmp_path, BOXES + ITEMS, f'{attr}="{value}"')
    [issue] = info.value.issues
    assert (issue.line, issue.column, issue.attribute) == (2, 26, attr) and valid in issue.message


def test_box_inner_corners_must_be_ordered() -> None:
    """box_inner's first corner must be below the second on every axis."""
    with pytest.raises(ValidationError, match="the corners must satisfy x0 < x1"):
        RefereeConfig.model_validate({"box_inner": "0.1 0 0 -0.1 1 1"})


def test_world_error_points_at_the_attribute(tmp_path: Path) -> None:
    """An invalid attribute in a world file is a WorldError at file:line:column of that attribute."""
    with pytest.raises(WorldError) as info:
        make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" wrong_box="minus"')
    assert str(info.value).startswith(f"{tmp_path / 'world.xml'}:2:42: <plugin> attribute 'wrong_box': 'minus' is "
                                      "not an integer")


def test_item_that_no_box_accepts_is_a_world_error(tmp_path: Path) -> None:
    """rules="cleanup" refuses a world where a trash item shares no tag with any trash box, listing the boxes."""
    body = BOXES + ITEMS.replace('tags="trash can"', 'tags="trash glass"')
    with pytest.raises(WorldError, match=r"no trash box \(tag 'trashbox'\) accepts 'can_0' \(tags glass\); boxes: "
                                         r"box_can: can; box_pet: petbottle recyclable"):
        make_sim(tmp_path, body)


def test_robots_attribute_must_name_robots(tmp_path: Path) -> None:
    """robots="..." naming an object is refused at the robots attribute."""
    with pytest.raises(WorldError, match="attribute 'robots': 'can_0' is not a robot") as info:
        make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" robots="can_0"')
    assert (info.value.issues[0].line, info.value.issues[0].column) == (2, 42)
