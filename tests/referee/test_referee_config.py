"""The plugin's attributes: defaults, and errors that name the attribute and what is valid."""

from __future__ import annotations

from pathlib import Path

import pytest
from referee_worlds import BOXES, ITEMS, make_sim
from sigcore_referee.config import RefereeConfig

from sigcore.world import WorldError


def test_defaults_are_the_issue_points() -> None:
    """With no attributes: service only, +1000 / -600 / +50 / -100, 600 s limit, 0.5 s debounce."""
    c = RefereeConfig.from_attributes({})
    assert (c.rules, c.service) == ("none", "referee")
    assert (c.correct_box, c.wrong_box, c.grasp, c.collision) == (1000, -600, 50, -100)
    assert (c.time_limit, c.debounce, c.rest_time) == (600.0, 0.5, 0.5)
    assert c.collision_tags == ("furniture", "wall") and c.floor and not c.stop_on_finish


def test_strings_are_converted() -> None:
    """Points, times, tag lists, corners and booleans are read from their attribute strings."""
    c = RefereeConfig.from_attributes({"rules": "cleanup", "correct_box": "+500", "time_limit": "90.5",
                                       "collision_tags": "wall  furniture trashbox", "stop_on_finish": "true",
                                       "box_inner": "-0.1 -0.1 0 0.1 0.1 0.3", "floor_parts": "a b"})
    assert (c.correct_box, c.time_limit, c.stop_on_finish) == (500, 90.5, True)
    assert c.collision_tags == ("wall", "furniture", "trashbox") and c.floor_parts == ("a", "b")
    assert c.box_inner == (-0.1, -0.1, 0.0, 0.1, 0.1, 0.3)


def test_unknown_attribute_suggests_the_close_one() -> None:
    """A misspelt attribute is refused with the closest valid name and the list of valid ones."""
    with pytest.raises(ValueError, match=r"unknown attribute 'corect_box' \(did you mean 'correct_box'\?\); valid:"):
        RefereeConfig.from_attributes({"corect_box": "1000"})


@pytest.mark.parametrize(("attr", "value", "valid"), [
    ("collision", "-1.5", "an integer number of points"),
    ("grasp", "many", "an integer number of points"),
    ("rules", "robocup", "'cleanup' or 'none'"),
    ("time_limit", "-1", "seconds >= 0"),
    ("box_inner", "0 0 0 1 1", "x0 y0 z0 x1 y1 z1"),
    ("stop_on_finish", "maybe", "'true' or 'false'"),
])
def test_bad_value_names_attribute_and_valid_values(attr: str, value: str, valid: str) -> None:
    """A bad value is refused naming the attribute, the value given and what is valid."""
    with pytest.raises(ValueError, match=f"attribute '{attr}'") as info:
        RefereeConfig.from_attributes({attr: value})
    assert repr(value) in str(info.value) and valid in str(info.value)


def test_box_inner_corners_must_be_ordered() -> None:
    """box_inner's first corner must be below the second on every axis."""
    with pytest.raises(ValueError, match=r"attribute .box_inner.=.0.1 0 0 -0.1 1 1.: the corners must satisfy x0 < x1"):
        RefereeConfig.from_attributes({"box_inner": "0.1 0 0 -0.1 1 1"})


def test_world_error_points_at_the_plugin_element(tmp_path: Path) -> None:
    """An invalid attribute in a world file is a WorldError located on the <plugin> line."""
    with pytest.raises(WorldError) as info:
        make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" wrong_box="minus"')
    text = str(info.value)
    assert "world.xml:2:" in text and "plugin 'referee'" in text and "attribute 'wrong_box'" in text


def test_item_that_no_box_accepts_is_a_world_error(tmp_path: Path) -> None:
    """rules="cleanup" refuses a world where a trash item shares no tag with any trash box, listing the boxes."""
    body = BOXES + ITEMS.replace('tags="trash can"', 'tags="trash glass"')
    with pytest.raises(WorldError, match=r"no trash box \(tag 'trashbox'\) accepts 'can_0' \(tags glass\); boxes: "
                                         r"box_can: can; box_pet: petbottle recyclable"):
        make_sim(tmp_path, body)


def test_robots_attribute_must_name_robots(tmp_path: Path) -> None:
    """robots="..." naming an object is refused."""
    with pytest.raises(WorldError, match="attribute 'robots': 'can_0' is not a robot"):
        make_sim(tmp_path, BOXES + ITEMS, 'rules="cleanup" robots="can_0"')
