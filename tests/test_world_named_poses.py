"""``<named_pose>`` in the world file: parsed into World.named_poses, every problem located at file:line:column."""

from __future__ import annotations

from pathlib import Path

import pytest

from sigcore.world import NamedPose, Pose, WorldError, WorldIssue, parse_world

URDF = Path(__file__).parent / "data" / "worlds" / "models" / "tinybot.urdf"


def _parse(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "world.xml"
    path.write_text(f'<world>\n  <robot name="bot" urdf="{URDF}" pose="1 2 0 0 0 0.5"/>\n{body}</world>\n',
                    encoding="utf-8")
    return path


def _issues(path: Path) -> list[WorldIssue]:
    with pytest.raises(WorldError) as info:
        parse_world(path)
    return info.value.issues


def test_named_poses_are_parsed_with_their_attributes(tmp_path: Path) -> None:
    """A named pose keeps name, pose, tags, description and bounds; the robot's start pose follows the file's."""
    world = parse_world(_parse(tmp_path, (
        '  <named_pose name="drop_0" pose="-2.1 -1.68 0 0 0 -1.5708" tags="drop navigation_goal"\n'
        '              description="drop here" bounds="-0.3 -0.3 0 0.3 0.3 1.5"/>\n'
        '  <named_pose name="goal" pose="1 1 0"/>\n')))
    drop, goal = world.named_poses
    assert drop == NamedPose(name="drop_0", pose=Pose(xyz=(-2.1, -1.68, 0.0), rpy=(0.0, 0.0, -1.5708)),
                             tags=("drop", "navigation_goal"), description="drop here",
                             bounds=(-0.3, -0.3, 0.0, 0.3, 0.3, 1.5))
    assert (goal.tags, goal.description, goal.bounds) == ((), "", None)
    start = world.all_named_poses()[-1]
    assert (start.name, start.tags, start.bounds) == ("bot_start", ("spawn", "start"), None)
    assert start.pose == Pose(xyz=(1.0, 2.0, 0.0), rpy=(0.0, 0.0, 0.5))


@pytest.mark.parametrize(("body", "line", "column", "attribute", "says"), [
    ('  <named_pose name="a" pose="0 0 0"/>\n  <named_pose name="a" pose="1 0 0"/>\n', 4, 15, "name",
     "duplicate name 'a' (first on line 3); every named pose needs its own name"),
    ('  <named_pose name="bot_start" pose="0 0 0"/>\n', 3, 15, "name",
     "'bot_start' is the automatic start pose of robot 'bot'; valid: another name"),
    ('  <named_pose name="a" pose="0 0 0" bounds="0 0 0 1 -1 1"/>\n', 3, 37, "bounds",
     "is not min < max on every axis"),
    ('  <named_pose name="a" pose="0 0 0" bounds="1 2 3"/>\n', 3, 37, "bounds", "expected 6 numbers, got 3"),
    ('  <named_pose name="a" pose="0 0 nan"/>\n', 3, 24, "pose", "numbers must be finite"),
    ('  <named_pose name="a"/>\n', 3, 3, None, "required attribute 'pose' is missing"),
    ('  <named_pose name="a" pose="0 0 0" colour="1"/>\n', 3, 37, "colour", "unknown attribute"),
    ('  <named_pose name="1a" pose="0 0 0"/>\n', 3, 15, "name", "name"),
    ('  <named_pose name="a" pose="0 0 0"><x/></named_pose>\n', 3, 37, None, "no child elements"),
])
def test_bad_named_poses_are_located(tmp_path: Path, body: str, line: int, column: int, attribute: str | None,
                                     says: str) -> None:
    """Each problem of a named pose is one issue at its file:line:column, naming what is valid."""
    issues = _issues(_parse(tmp_path, body))
    assert len(issues) == 1, "\n".join(map(str, issues))
    issue = issues[0]
    assert (issue.line, issue.column, issue.attribute) == (line, column, attribute), str(issue)
    assert says in issue.message, issue.message
