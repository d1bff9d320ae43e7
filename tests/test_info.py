"""Entity information (sigcore/sim/info.py): category, description and tags, one owner, validated, reset."""

from __future__ import annotations

from pathlib import Path

import pytest

from sigcore.agent.exceptions import ApiError
from sigcore.sim import Simulation
from sigcore.sim.info import CATEGORIES, EntityInfo, EntityInfos, named_poses_with_tags
from sigcore.world import parse_world
from sigcore.world.models import MAX_DESCRIPTION, MAX_TAG_LENGTH, MAX_TAGS

WORLD = """<world>
  <robot name="bot" urdf="{urdf}" tags="mobile helper" description="the helper"/>
  <object name="can" shape="cylinder" size="0.03 0.1" tags="trash can"/>
  <object name="table" shape="box" size="1 1 0.7" static="true" tags="furniture"/>
  <human name="man" static="false"/>
  <agent name="moderator"/>
  <named_pose name="drop" pose="1 2 0 0 0 1.5" tags="drop navigation_goal" description="by the box"
              bounds="-0.3 -0.3 0 0.3 0.3 1.5"/>
</world>
"""
URDF = Path(__file__).parent / "data" / "worlds" / "models" / "tinybot.urdf"


@pytest.fixture
def infos(tmp_path: Path) -> EntityInfos:
    """The entity information of the small world above."""
    path = tmp_path / "world.xml"
    path.write_text(WORLD.format(urdf=URDF), encoding="utf-8")
    return EntityInfos(parse_world(path).entities)


def test_initial_values_come_from_the_world_file(infos: EntityInfos) -> None:
    """Robots are 'robot', humans 'human' (static or not), static objects 'static_object', other objects 'object';
    description and tags are the file's (empty when absent); bare agents are not entities."""
    assert infos.names == ["bot", "can", "table", "man"]
    assert infos.get("bot") == EntityInfo("robot", "the helper", ("mobile", "helper"))
    assert infos.get("can") == EntityInfo("object", "", ("trash", "can"))
    assert infos.get("table") == EntityInfo("static_object", "", ("furniture",))
    assert infos.get("man") == EntityInfo("human", "", ())


def test_set_replaces_all_three_and_filters_see_it(infos: EntityInfos) -> None:
    """set replaces category, description and tags; with_tags and in_categories read the new values."""
    infos.set("can", "dynamic_object", "a red can", ["trash", "red"])
    assert infos.get("can") == EntityInfo("dynamic_object", "a red can", ("trash", "red"))
    assert infos.with_tags(["red"]) == ["can"]
    assert infos.with_tags(["can"]) == []
    assert infos.with_tags(["trash", "red"], match_all=True) == ["can"]
    assert infos.with_tags(["red", "furniture"]) == ["can", "table"]
    assert infos.with_tags([]) == infos.names
    assert infos.in_categories(["dynamic_object", "human"]) == ["can", "man"]


@pytest.mark.parametrize(("category", "description", "tags", "says"), [
    ("furniture", "", [], "is not one of object, robot, human, dynamic_object, static_object"),
    ("object", "", [""], "is empty"),
    ("object", "", ["two words"], "whitespace"),
    ("object", "", ["tab\there"], "whitespace"),
    ("object", "", ["bell\x07"], "control characters"),
    ("object", "", ["x" * (MAX_TAG_LENGTH + 1)], f"at most {MAX_TAG_LENGTH}"),
    ("object", "", [f"t{i}" for i in range(MAX_TAGS + 1)], f"at most {MAX_TAGS}"),
    ("object", "d" * (MAX_DESCRIPTION + 1), [], f"at most {MAX_DESCRIPTION}"),
])
def test_bad_values_are_refused_and_change_nothing(infos: EntityInfos, category: str, description: str,
                                                   tags: list[str], says: str) -> None:
    """A bad category, tag or description is refused with the rule it breaks; the entity keeps its values."""
    before = infos.get("can")
    with pytest.raises(ApiError, match=says.replace("(", r"\(")):
        infos.set("can", category, description, tags)
    assert infos.get("can") == before


def test_unknown_entity_is_refused_listing_the_entities(infos: EntityInfos) -> None:
    """get and set of an unknown entity raise ApiError naming it and listing the entities."""
    with pytest.raises(ApiError, match="no entity 'moderator'; entities: bot, can, table, man"):
        infos.get("moderator")
    with pytest.raises(ApiError, match="no entity 'nobody'"):
        infos.set("nobody", "object", "", [])


def test_reset_restores_the_world_files_values(infos: EntityInfos) -> None:
    """reset puts back the world file's category, description and tags."""
    initial = infos.get("bot")
    infos.set("bot", "object", "changed", ["x"])
    infos.reset()
    assert infos.get("bot") == initial


def test_simulation_owns_the_information_and_its_reset_restores_it(sim: Simulation) -> None:
    """sim.entities.info starts from the world file and Simulation.reset restores it."""
    info = sim.entities.info
    assert info.get("cube").tags == ("trash",) and info.get("wall").category == "static_object"
    sim.entities.info.set("cube", "object", "moved to the bin", ["done"])
    sim.reset()
    assert sim.entities.info.get("cube") == EntityInfo("object", "", ("trash",))


def test_categories_name_the_standard_constants() -> None:
    """The core's categories are the five EntityCategory constants' names, lower case."""
    assert CATEGORIES == ("object", "robot", "human", "dynamic_object", "static_object")


def test_named_poses_filtered_by_tags(tmp_path: Path) -> None:
    """The file's named poses and each robot's '<robot>_start' (tags spawn start), filtered ANY or ALL."""
    path = tmp_path / "world.xml"
    path.write_text(WORLD.format(urdf=URDF), encoding="utf-8")
    poses = parse_world(path).all_named_poses()
    assert [p.name for p in poses] == ["drop", "bot_start"]
    assert [p.name for p in named_poses_with_tags(poses, [])] == ["drop", "bot_start"]
    assert [p.name for p in named_poses_with_tags(poses, ["spawn", "drop"])] == ["drop", "bot_start"]
    assert [p.name for p in named_poses_with_tags(poses, ["spawn", "drop"], match_all=True)] == []
    assert [p.name for p in named_poses_with_tags(poses, ["navigation_goal", "drop"], match_all=True)] == ["drop"]
