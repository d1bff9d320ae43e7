"""The read side of simulation_interfaces (entity information, bounds, filters, named poses, simulate_steps
feedback) on worlds/cleanup.xml, asked by a client in another process."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import start_sim  # noqa: E402

pytestmark = pytest.mark.ros2

CLEANUP = Path(__file__).resolve().parents[2] / "worlds" / "cleanup.xml"
OK, FEATURE_UNSUPPORTED, NOT_FOUND, OPERATION_FAILED = 1, 0, 2, 4
OBJECT, ROBOT, HUMAN, DYNAMIC, STATIC = 0, 1, 2, 4, 5
BOX, EMPTY = 1, 0


@pytest.fixture(scope="module")
def out(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict]:
    """What clients/siminfo.py saw of a paused simulation of worlds/cleanup.xml."""
    sim = start_sim(tmp_path_factory.mktemp("siminfo"), CLEANUP, "--paused")
    try:
        yield sim.client("siminfo.py", timeout=120)
    finally:
        sim.stop()


def test_features_list_the_read_side(out: dict) -> None:
    """get_simulator_features lists named poses, pose bounds, entity bounds (box), categories and entity info
    getting and setting, besides what was there (spawning and deleting: test_spawn_ros2.py; worlds:
    test_worlds_ros2.py); nothing unsupported (convex hulls)."""
    assert out["features"] == [0, 1, 2, 3, 4, 5, 6, 8, 9, 10, 11, 12, 13, 14, 20, 22, 23, 24, 25, 26, 31, 32, 33, 40,
                               41, 42, 43, 44, 45, 50]


def test_entity_info_is_the_world_files(out: dict) -> None:
    """get_entity_info returns the world file's tags, an empty description, and the category of each kind."""
    info = out["info"]
    assert all(i["result"] == OK and i["description"] == "" for i in info.values())
    assert (info["can_0"]["category"], info["can_0"]["tags"]) == (OBJECT, ["trash", "can"])
    assert (info["table_0"]["category"], info["table_0"]["tags"]) == (STATIC, ["furniture"])
    assert (info["trashbox_2"]["category"], info["trashbox_2"]["tags"]) == (STATIC, ["trashbox", "can"])
    assert (info["robot_000"]["category"], info["man_0"]["category"]) == (ROBOT, HUMAN)


def test_set_entity_info_is_seen_by_get_and_filters(out: dict) -> None:
    """After set_entity_info, get_entity_info and the tag and category filters of get_entities see the change."""
    assert out["set"]["result"] == OK
    assert out["after_set"] | {"message": ""} == {"result": OK, "message": "", "category": DYNAMIC,
                                                  "description": "a red can", "tags": ["trash", "can", "red"]}
    assert out["tag_red"]["entities"] == ["can_0"]
    assert out["tag_all"]["entities"] == ["can_0"]
    assert out["dynamic"]["entities"] == ["can_0"]
    assert out["humans_robots"]["entities"] == ["robot_000", "man_0"]


def test_table_bounds_agree_with_its_geometry(out: dict) -> None:
    """get_entity_bounds of table_0 is the box of table.urdf at (-1.5, 1.9): x -2.10..-0.90, y 1.60..2.20,
    z 0..0.70 (top 0.68 + 0.02), within 1e-6 m."""
    b = out["table_bounds"]
    assert (b["result"], b["type"]) == (OK, BOX)
    assert b["points"][0] == pytest.approx([-2.1, 1.6, 0.0], abs=1e-6)
    assert b["points"][1] == pytest.approx([-0.9, 2.2, 0.7], abs=1e-6)


def test_bounds_filters_select_overlapping_entities(out: dict) -> None:
    """A 5 cm sphere around can_0 returns can_0 and not the robot; a box inside trashbox_0 returns only it (its
    corners given upper first)."""
    assert out["sphere_can"]["result"] == OK
    assert "can_0" in out["sphere_can"]["entities"] and "robot_000" not in out["sphere_can"]["entities"]
    assert out["box_bin"] == {"result": OK, "message": "", "entities": ["trashbox_0"]}


def test_named_poses_are_listed_with_tags_and_bounds(out: dict) -> None:
    """get_named_poses lists the file's pick and drop poses and robot_000_start (tags spawn start, its world-file
    pose), filtered by tags; get_named_pose_bounds gives the file's box moved to the pose, empty without one."""
    poses = out["poses"]
    assert out["poses_result"] == OK and len(poses) == 10
    assert poses["robot_000_start"]["tags"] == ["spawn", "start"]
    assert poses["robot_000_start"]["pose"] == pytest.approx([-4.0, 0, 0, 1, 0, 0, 0], abs=1e-9)
    drop = poses["drop_trashbox_0_left"]
    assert drop["tags"] == ["drop", "navigation_goal", "trashbox_0", "left_arm"]
    half = -1.5707963 / 2  # half the yaw [rad]
    assert drop["pose"] == pytest.approx([-2.1, -1.68, 0, math.cos(half), 0, 0, math.sin(half)], abs=1e-9)
    assert out["poses_spawn"] == ["robot_000_start"]
    assert out["poses_drop_0"] == ["drop_trashbox_0_left", "drop_trashbox_0_right"]
    b = out["pose_bounds"]
    assert (b["result"], b["type"]) == (OK, BOX)
    assert b["points"][0] == pytest.approx([-2.4, -1.98, 0.0], abs=1e-9)
    assert b["points"][1] == pytest.approx([-1.8, -1.38, 1.5], abs=1e-9)
    assert out["start_bounds"] == {"result": OK, "type": EMPTY, "points": []}


def test_simulate_steps_gives_one_feedback_per_step(out: dict) -> None:
    """A 20-step simulate_steps goal succeeds with 20 feedbacks: completed 1..20, remaining 19..0."""
    assert out["action"] == OK
    assert out["feedback"] == [[i, 20 - i] for i in range(1, 21)]


@pytest.mark.parametrize(("case", "code", "says"), [
    ("info_unknown", NOT_FOUND, "no entity 'nobody'; entities: robot_000, wall_north"),
    ("info_agent", NOT_FOUND, "no entity 'moderator_0'"),
    ("set_unknown", NOT_FOUND, "no entity 'nobody'"),
    ("set_category", OPERATION_FAILED, "category 3 is unknown; valid: 0 CATEGORY_OBJECT, 1 CATEGORY_ROBOT"),
    ("set_tag_space", OPERATION_FAILED, "tag 'two words' holds whitespace"),
    ("set_tag_empty", OPERATION_FAILED, "is empty"),
    ("bounds_unknown", NOT_FOUND, "no entity 'nobody'"),
    ("filter_nan", OPERATION_FAILED, "TYPE_BOX bounds points must be finite numbers [m]"),
    ("filter_radius", OPERATION_FAILED, "TYPE_SPHERE radius (points[1].x) is -1; valid: >= 0 [m]"),
    ("filter_points", OPERATION_FAILED, "TYPE_SPHERE bounds with 1 points; valid: exactly 2"),
    ("filter_hull", FEATURE_UNSUPPORTED, "TYPE_CONVEX_HULL bounds are not supported"),
    ("filter_type", OPERATION_FAILED, "bounds type 7 is unknown; valid: 0 TYPE_EMPTY, 1 TYPE_BOX"),
    ("filter_regex", OPERATION_FAILED, "filter 'can_([' is not a regular expression"),
    ("filter_category", OPERATION_FAILED, "category 3 is unknown; valid: 0 CATEGORY_OBJECT"),
    ("filter_mode", OPERATION_FAILED, "tags filter_mode 5 is unknown; valid: 0 FILTER_MODE_ANY, 1 FILTER_MODE_ALL"),
    ("pose_unknown", NOT_FOUND, "no named pose 'nowhere'; named poses: pick_can_0"),
])
def test_bad_input_gets_the_standard_code_and_says_why(out: dict, case: str, code: int, says: str) -> None:
    """Each bad request gets the standard Result code and a message naming what was wrong and what is valid."""
    result, message = out["bad"][case]
    assert result == code, message
    assert says in message, message


def test_refused_sets_change_nothing_and_reset_restores(out: dict) -> None:
    """Refused set_entity_info calls leave the last accepted values; reset_simulation restores the world file's."""
    assert (out["after_bad"]["category"], out["after_bad"]["tags"]) == (DYNAMIC, ["trash", "can", "red"])
    assert out["reset"] == OK
    assert out["after_reset"] | {"message": ""} == {"result": OK, "message": "", "category": OBJECT,
                                                    "description": "", "tags": ["trash", "can"]}
