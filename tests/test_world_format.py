"""The world file format: every malformed file is reported at its exact ``line:column``, with what is valid.

The malformed worlds live in ``tests/data/worlds/bad/`` (one problem each, explained in a comment on line 1),
so they double as examples for users; ``tests/data/worlds/valid/full.xml`` uses every element.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import annotated_types
import pytest
from pydantic import BaseModel, ValidationError
from pydantic.fields import FieldInfo

from sigcore.world import (
    Arm,
    BareAgent,
    Camera,
    Drive,
    Gains,
    Gripper,
    Human,
    Lidar,
    NamedPose,
    Object,
    PluginConfig,
    Pose,
    Robot,
    WalkPath,
    Waypoint,
    World,
    WorldError,
    WorldIssue,
    parse_world,
)
from sigcore.world.messages import literal_values, value_range

WORLDS = Path(__file__).parent / "data" / "worlds"
BAD = WORLDS / "bad"
MODELS = WORLDS / "models"
DOCS = Path(__file__).parent.parent / "docs" / "world-format.md"


@dataclass(frozen=True)
class Bad:
    """A malformed world file and the one issue it must produce."""

    file: str
    line: int
    column: int
    element: str | None
    attribute: str | None
    says: tuple[str, ...]  # fragments of the message: what is wrong, what would be valid


BAD_FILES = [
    Bad("not_well_formed.xml", 4, 9, None, None,
        ("not well-formed XML", "Opening and ending tag mismatch: object line 3 and world")),
    Bad("wrong_root.xml", 2, 1, "scene", None, ("root element is <scene>", "valid: <world>")),
    Bad("unknown_top_element.xml", 3, 3, "robt", None,
        ("unknown element inside <world>", "did you mean 'robot'?",
         "valid: plugin, named_pose, robot, object, human, agent")),
    Bad("unknown_robot_child.xml", 4, 5, "sonar", None,
        ("unknown element inside <robot>", "valid: drive, lidar, camera, gripper, arm, gains")),
    Bad("camera_unknown_link.xml", 4, 25, "camera", "link",
        ("no link 'head_link' in ../models/tinybot.urdf",
         "valid: base_link, wheel_l_link, wheel_r_link, laser_link, hand_link")),
    Bad("duplicate_camera.xml", 5, 13, "camera", "name",
        ("duplicate name 'eye'", "first on line 4", "each camera of a robot needs its own name")),
    Bad("camera_near_far.xml", 4, 5, "camera", None, ("near 5 must be less than far 2",)),
    Bad("camera_principal_outside.xml", 4, 64, "camera", "principal",
        ("principal point (70, 20) lies outside the 64x48 image", "valid: 0 <= cx <= 63, 0 <= cy <= 47")),
    Bad("camera_bad_type.xml", 4, 41, "camera", "type", ("'stereo'", "rgb", "depth", "rgbd")),
    Bad("camera_frame_is_a_link.xml", 4, 13, "camera", "name",
        ("would add the frame 'laser_link', which is a link of ../models/tinybot.urdf",)),
    Bad("unknown_attribute.xml", 3, 49, "object", "colour",
        ("unknown attribute", "did you mean 'color'?",
         "valid: color, controller, description, friction, graspable, mass, mesh, name, pose, scale, shape, size, "
         "static, tags, urdf")),
    Bad("missing_name.xml", 3, 3, "object", None, ("required attribute 'name' is missing",)),
    Bad("missing_urdf.xml", 3, 3, "robot", None, ("required attribute 'urdf' is missing",)),
    Bad("missing_drive_left.xml", 4, 5, "drive", None,
        ("required attribute 'left' is missing", "left wheel joint name")),
    Bad("bad_shape.xml", 3, 24, "object", "shape",
        ("'cube' is not valid", "valid: box, sphere, cylinder, capsule")),
    Bad("not_a_number.xml", 3, 55, "object", "mass", ("'heavy' is not a number",)),
    Bad("nan_mass.xml", 3, 55, "object", "mass", ("'nan' is not a finite number", "NaN and infinity")),
    Bad("inf_pose.xml", 3, 55, "object", "pose", ("numbers must be finite", "'1 inf 0.05'")),
    Bad("pose_two_numbers.xml", 3, 23, "human", "pose",
        ("expected 3 or 6 numbers, got 2 ('3 2')", "valid: 'x y z' or 'x y z roll pitch yaw'")),
    Bad("gravity_two_numbers.xml", 2, 8, "world", "gravity", ("expected 3 numbers, got 2 ('0 -9.81')",)),
    Bad("negative_mass.xml", 3, 55, "object", "mass",
        ("'-1' is out of range", "valid: 0 < mass <= 100000 [kg]")),
    Bad("timestep_zero.xml", 2, 23, "world", "timestep",
        ("'0' is out of range", "valid: 0 < timestep <= 0.1 [s]")),
    Bad("beams_zero.xml", 4, 47, "lidar", "beams", ("'0' is out of range", "valid: 1 <= beams <= 10000")),
    Bad("beams_not_integer.xml", 4, 47, "lidar", "beams", ("'360.5' is not an integer",)),
    Bad("fov_too_large.xml", 4, 47, "lidar", "fov",
        ("'360' is out of range", "valid: 0 < fov <= 6.28319 [rad]")),
    Bad("lidar_range_inverted.xml", 4, 47, "lidar", "range",
        ("min 10 and max 0.05 do not satisfy 0 <= min < max", "valid: 'min max' [m]")),
    Bad("grasp_radius_zero.xml", 4, 31, "gripper", "grasp_radius",
        ("'0' is out of range", "valid: 0 < grasp_radius <= 2 [m]")),
    Bad("size_count.xml", 3, 41, "object", "size",
        ("expected 2 numbers for a cylinder, got 3", "valid: 'radius length' [m]")),
    Bad("shape_and_mesh.xml", 3, 55, "object", "mesh",
        ("'shape' and 'mesh' are both given", "exactly one of 'shape', 'mesh' or 'urdf'")),
    Bad("no_geometry.xml", 3, 3, "object", None,
        ("no geometry", "valid: one of 'shape' (with 'size'), 'mesh' or 'urdf'")),
    Bad("size_on_mesh.xml", 3, 47, "object", "size",
        ("'size' is only for primitive shapes", "a mesh object uses 'scale'")),
    Bad("scale_on_shape.xml", 3, 49, "object", "scale",
        ("'scale' is only for 'mesh' and 'urdf' objects", "sized by 'size' ('radius')")),
    Bad("color_out_of_range.xml", 3, 49, "object", "color",
        ("components must be in [0, 1], got 255 0 0 1", "valid: 'r g b a'")),
    Bad("bad_boolean.xml", 3, 54, "object", "static",
        ("'yes please' is not a boolean", "valid: true, false")),
    Bad("duplicate_agent_name.xml", 5, 11, "object", "name",
        ("duplicate name 'can_0'", "first on line 3", "every agent needs its own name")),
    Bad("invalid_name_dash.xml", 3, 10, "robot", "name",
        ("invalid name 'robot-1'", "valid: a letter, then letters, digits or '_'", "ROS 2 topic names")),
    Bad("invalid_name_digit.xml", 3, 10, "human", "name",
        ("invalid name '2nd_man'", "valid: a letter, then letters, digits or '_'")),
    Bad("urdf_missing.xml", 3, 27, "robot", "urdf",
        (f"file not found: {BAD / 'models' / 'tinybot.urdf'}",
         "relative paths start at the world file's directory")),
    Bad("urdf_not_xml.xml", 3, 27, "robot", "urdf",
        (f"invalid URDF: {MODELS / 'not_xml.urdf'}:3: not valid XML",)),
    Bad("urdf_no_links.xml", 3, 27, "robot", "urdf",
        (f"invalid URDF: {MODELS / 'no_links.urdf'}:2: no <link> in the robot",)),
    Bad("object_urdf_no_links.xml", 3, 24, "object", "urdf", ("invalid URDF", "no <link> in the robot")),
    Bad("drive_unknown_joint.xml", 4, 12, "drive", "left",
        ("no movable joint 'left_wheel' in ../models/tinybot.urdf",
         "valid: arm_joint, wheel_l_joint, wheel_r_joint")),
    Bad("lidar_unknown_link.xml", 4, 29, "lidar", "link",
        ("no link 'base_laser' in ../models/tinybot.urdf",
         "valid: base_link, wheel_l_link, wheel_r_link, laser_link, hand_link")),
    Bad("duplicate_lidar.xml", 5, 12, "lidar", "name",
        ("duplicate name 'scan'", "first on line 4", "each lidar of a robot needs its own name")),
    Bad("drive_twice.xml", 5, 5, "drive", None,
        ("<drive> may appear only once in a <robot>", "first on line 4")),
    Bad("text_content.xml", 5, 5, "robot", None,
        ("unexpected text 'max speed 1 m/s'", "<robot> holds only elements")),
    Bad("element_inside_object.xml", 4, 5, "pose", None,
        ("unexpected element", "<object> has no child elements, only attributes")),
    Bad("plugin_without_name.xml", 3, 3, "plugin", None,
        ("required attribute 'name' is missing", "the plugin to enable")),
    Bad("plugin_twice.xml", 5, 13, "plugin", "name",
        ("duplicate name 'slam'", "first on line 3", "enable a plugin once")),
    Bad("mesh_missing.xml", 3, 22, "object", "mesh", (f"file not found: {MODELS / 'cup.obj'}",)),
    Bad("multiline_attribute.xml", 5, 39, "object", "mass", ("'0' is out of range", "valid: 0 < mass")),
    Bad("attribute_in_value.xml", 3, 67, "object", "mass", ("'0' is out of range",)),
]


def _issues(path: Path | str, text: str | None = None) -> list[WorldIssue]:
    with pytest.raises(WorldError) as info:
        parse_world(path, text)
    return info.value.issues


def _world(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "world.xml"
    path.write_text(text, encoding="utf-8")
    return path


# ------------------------------------------------------------------------------------------ malformed files


@pytest.mark.parametrize("bad", BAD_FILES, ids=[b.file.removesuffix(".xml") for b in BAD_FILES])
def test_malformed_world_reports_one_located_issue(bad: Bad) -> None:
    """Each malformed file gives one issue at its exact line:column, saying what is wrong and what's valid."""
    issues = _issues(BAD / bad.file)
    assert len(issues) == 1, "\n".join(map(str, issues))
    issue = issues[0]
    assert (issue.line, issue.column) == (bad.line, bad.column), str(issue)
    assert (issue.element, issue.attribute) == (bad.element, bad.attribute), str(issue)
    for fragment in bad.says:
        assert fragment in issue.message, f"{fragment!r} not in {issue.message!r}"
    assert issue.file == BAD / bad.file


def test_every_bad_file_is_tested() -> None:
    """Every file in tests/data/worlds/bad/ has an expectation here (a new example cannot go untested)."""
    tested = {b.file for b in BAD_FILES} | {"several_errors.xml"}
    assert {p.name for p in BAD.glob("*.xml")} == tested


def test_several_errors_are_all_reported_sorted_by_line() -> None:
    """One parse reports every problem of the file, sorted by line, including checks against the URDF."""
    issues = _issues(BAD / "several_errors.xml")
    assert [(i.line, i.column, i.attribute) for i in issues] == [
        (2, 8, "timestep"), (3, 57, "pose"), (4, 29, "link"), (6, 24, "shape"), (7, 23, "height"),
    ]
    assert "valid: 0.3 < height <= 2.5 [m]" in issues[-1].message
    error = WorldError(issues)
    assert str(error).count("\n") == len(issues) - 1


def test_issue_text_has_file_line_column_element_and_attribute() -> None:
    """An issue prints as 'file:line:column: <element> attribute 'x': message'."""
    issue = _issues(BAD / "negative_mass.xml")[0]
    assert str(issue) == (f"{BAD / 'negative_mass.xml'}:3:55: <object> attribute 'mass': "
                          "'-1' is out of range; valid: 0 < mass <= 100000 [kg]")
    root = _issues(BAD / "wrong_root.xml")[0]
    assert str(root).startswith(f"{BAD / 'wrong_root.xml'}:2:1: <scene>: ")


def test_message_does_not_repeat_the_value() -> None:
    """The offending value appears once in a message (no duplicated '(got ...)')."""
    for name in ("negative_mass.xml", "pose_two_numbers.xml", "inf_pose.xml", "bad_shape.xml"):
        message = _issues(BAD / name)[0].message
        assert message.count("got") <= 1 and "(got" not in message, message


def test_comments_with_tags_do_not_shift_locations(tmp_path: Path) -> None:
    """Comments and processing instructions, even multi-line or holding '<tag', leave line:column exact."""
    path = _world(tmp_path, (
        '<?xml version="1.0"?>\n'
        '<?sigcore hint="<object>"?>\n'
        '<world> <!-- <object name="a" mass="-1"/> -->\n'
        '  <!-- <robot name="r"\n'
        '       urdf="x"/> -->\n'
        '  <object name="b" shape="sphere" size="0.1" mass="-2"/>\n'
        "</world>\n"
    ))
    issues = _issues(path)
    assert [(i.line, i.column, i.attribute) for i in issues] == [(6, 46, "mass")]
    assert "'-2'" in issues[0].message


def test_text_inside_a_leaf_element_is_located_at_the_text(tmp_path: Path) -> None:
    """Text inside an element that takes only attributes is reported where the text starts."""
    path = _world(tmp_path, '<world>\n  <human name="h">\n     walking\n  </human>\n</world>\n')
    [issue] = _issues(path)
    assert (issue.line, issue.column, issue.element) == (3, 6, "human")
    assert "unexpected text 'walking'" in issue.message and "<human> holds only elements" in issue.message


def test_text_directly_inside_world_is_reported(tmp_path: Path) -> None:
    """Stray text between top-level elements (not only before the first one) is an error."""
    path = _world(tmp_path, '<world>\n  <agent name="a"/>\n  oops <agent name="b"/>\n</world>\n')
    [issue] = _issues(path)
    assert (issue.line, issue.column, issue.element) == (3, 3, "world")


def test_world_file_not_utf8_is_located(tmp_path: Path) -> None:
    """A file that is not UTF-8 is reported at the first bad byte, not with a traceback."""
    path = tmp_path / "latin1.xml"
    path.write_bytes('<world>\n  <agent name="caf\xe9"/>\n</world>\n'.encode("latin-1"))
    [issue] = _issues(path)
    assert (issue.line, issue.column) == (2, 19)
    assert "byte 0xe9 is not UTF-8" in issue.message


def test_missing_world_file_is_an_issue(tmp_path: Path) -> None:
    """A world file that does not exist raises WorldError naming the file."""
    [issue] = _issues(tmp_path / "nope.xml")
    assert issue.file == tmp_path / "nope.xml" and "cannot read world file" in issue.message


def test_urdf_with_non_numeric_limit_is_an_issue(tmp_path: Path) -> None:
    """A URDF joint limit that is not a number is reported on the robot's 'urdf', not raised as ValueError."""
    (tmp_path / "bot.urdf").write_text(
        '<robot name="b"><link name="a"/><link name="c"/>\n<joint name="j" type="revolute"><parent link="a"/>'
        '<child link="c"/>\n<limit lower="low" upper="1"/></joint></robot>\n')
    path = _world(tmp_path, '<world>\n  <robot name="r" urdf="bot.urdf"/>\n</world>\n')
    [issue] = _issues(path)
    assert (issue.line, issue.column, issue.attribute) == (2, 19, "urdf")
    assert "bot.urdf:3: joint 'j': <limit lower upper> must be numbers" in issue.message


def test_empty_path_is_an_issue(tmp_path: Path) -> None:
    """An empty 'urdf' or 'mesh' is reported instead of resolving to the world's directory."""
    path = _world(tmp_path, '<world>\n  <object name="o" mesh=""/>\n</world>\n')
    [issue] = _issues(path)
    assert (issue.line, issue.column, issue.attribute) == (2, 20, "mesh") and "empty path" in issue.message


@pytest.mark.parametrize(("attribute", "value"), [("scale", "inf"), ("friction", "nan"), ("mass", "-inf")])
def test_scalars_reject_nan_and_infinity(tmp_path: Path, attribute: str, value: str) -> None:
    """No float attribute accepts NaN or infinity, even one with only a lower bound."""
    path = _world(tmp_path, f'<world><object name="o" mesh="m.obj" {attribute}="{value}"/></world>')
    (tmp_path / "m.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n")
    [issue] = _issues(path)
    assert issue.attribute == attribute and "not a finite number" in issue.message


# ------------------------------------------------------------------------------------------ valid files


@pytest.fixture(scope="module")
def full() -> World:
    """The world that uses every element."""
    return parse_world(WORLDS / "valid" / "full.xml")


def test_full_world_parses_into_models(full: World) -> None:
    """Every element of full.xml becomes the expected model: rpy poses, split tags, plugin settings."""
    assert (full.name, full.timestep, full.gravity, full.seed) == ("kitchen", 0.001, (0.0, 0.0, -9.8), 7)
    assert [(p.name, p.config, p.location(), p.location(next(iter(p.config)))) for p in full.plugins] == [
        ("referee", {"rules": "cleanup"}, (4, 3), (4, 26)), ("slam", {"agent": "robot_000"}, (5, 3), (5, 23))]
    robot = full.agent("robot_000")
    assert isinstance(robot, Robot)
    assert robot.pose == Pose(xyz=(1.0, 0.3, 0.0), rpy=(0.0, 0.0, 1.5708))
    assert robot.urdf == Path("../models/tinybot.urdf") and robot.controller == "examples.cleanup:Robot"
    assert robot.tags == ("mobile", "helper")
    assert robot.drive == Drive(left="wheel_l_joint", right="wheel_r_joint", radius=0.05, separation=0.3,
                                max_wheel_velocity=10, max_torque=5)
    assert robot.lidars == (Lidar(name="base_scan", link="laser_link", beams=360, fov=2 * math.pi,
                                  range=(0.05, 10.0), rate=10, noise=0.01),)
    assert robot.grippers == (Gripper(part="hand_link", grasp_radius=0.08, side="right"),)
    assert robot.arms == (Arm(name="arm", base="base_link", tip="hand_link"),)
    assert robot.gains == Gains(kp=100, kv=5, max_torque=50)
    can = full.agent("can_0")
    assert isinstance(can, Object)
    assert (can.shape, can.size, can.mass, can.graspable) == ("cylinder", (0.033, 0.12), 0.05, True)
    assert can.tags == ("trash", "can") and can.color == (0.8, 0.1, 0.1, 1.0) and can.friction == 0.8
    assert can.pose == Pose(xyz=(2.7, 0.7, 0.75))
    mug = full.agent("mug")
    assert isinstance(mug, Object) and mug.mesh == Path("../models/mug.obj") and mug.scale == 1.5
    assert mug.pose.rpy == (0.0, 0.0, 0.5)
    assert full.agent("man_0") == Human(name="man_0", pose=Pose(xyz=(3.0, 2.0, 0.0)), height=1.8, mass=80)
    assert full.agent("moderator_0") == BareAgent(name="moderator_0", controller="cleanup.moderator")
    kinds = ["robot", "object", "object", "object", "object", "human", "agent"]
    assert [a.kind for a in full.agents] == kinds
    assert [e.name for e in full.entities] == ["robot_000", "can_0", "mug", "shelf", "floor_box", "man_0"]


def test_defaults(tmp_path: Path) -> None:
    """Omitted attributes take their defaults (timestep 0.002 s, gravity 0 0 -9.81, not static...)."""
    world = parse_world(_world(tmp_path, (
        '<world>\n  <object name="o" shape="box" size="1 1 1"/>\n  <human name="h"/>\n  <agent name="a"/>\n'
        "</world>\n")))
    assert (world.name, world.timestep, world.gravity, world.seed, world.plugins) == (
        "world", 0.002, (0.0, 0.0, -9.81), 0, ())
    obj = world.agent("o")
    assert isinstance(obj, Object)
    assert (obj.static, obj.graspable, obj.mass, obj.scale, obj.friction) == (False, False, 1.0, 1.0, 1.0)
    assert (obj.pose, obj.tags, obj.color, obj.controller) == (Pose(), (), (0.7, 0.7, 0.7, 1.0), None)
    human = world.agent("h")
    assert isinstance(human, Human) and (human.static, human.height, human.mass) == (True, 1.7, 70.0)
    lidar = Lidar(name="scan", link="base_link")
    assert (lidar.beams, lidar.fov, lidar.range) == (360, 2 * math.pi, (0.05, 10.0))
    assert (lidar.rate, lidar.noise) == (10, 0)
    assert Drive(left="l", right="r", radius=0.1, separation=0.4).type == "differential"
    assert Gripper(part="hand").grasp_radius == 0.1 and Gains() == Gains(kp=200, kv=10, max_torque=100)


def test_pose_with_three_numbers_has_zero_rotation() -> None:
    """'x y z' is a pose without rotation; 'x y z roll pitch yaw' keeps the angles in that order."""
    assert Pose.parse("1 2 3") == Pose(xyz=(1.0, 2.0, 3.0), rpy=(0.0, 0.0, 0.0))
    assert Pose.parse(" 1 2 3  0.1 0.2 0.3 ") == Pose(xyz=(1.0, 2.0, 3.0), rpy=(0.1, 0.2, 0.3))


def test_full_turn_fov_is_exactly_two_pi(full: World) -> None:
    """fov="6.2832" (2π rounded up) means a full turn, stored as exactly 2π; 6.3 is rejected."""
    robot = full.agent("robot_000")
    assert isinstance(robot, Robot) and robot.lidars[0].fov == 2 * math.pi
    with pytest.raises(ValidationError):
        Lidar(name="scan", link="l", fov="6.3")  # type: ignore[arg-type]


def test_location_points_at_element_and_attribute(full: World) -> None:
    """World.location() gives the line:column of an agent's element or of one of its attributes."""
    assert full.location("robot_000") == (8, 3)
    assert full.location("robot_000", "controller") == (9, 10)
    assert full.location("can_0", "graspable") == (19, 11)
    assert full.location("man_0", "no_such_attribute") == full.location("man_0") == (23, 3)
    assert full.location("nobody") == (0, 0)


def test_relative_paths_resolve_against_the_world_directory(full: World, tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """Model paths are relative to the world file's directory, whatever the current directory."""
    monkeypatch.chdir(tmp_path)
    robot = full.agent("robot_000")
    assert isinstance(robot, Robot)
    assert full.base_dir == WORLDS / "valid"
    assert full.resolve(robot.urdf).resolve() == (MODELS / "tinybot.urdf").resolve()
    assert full.resolve(Path("/abs/x.urdf")) == Path("/abs/x.urdf")
    relative = Path(os.path.relpath(WORLDS / "valid" / "full.xml", tmp_path))
    assert parse_world(relative).agent("mug") == full.agent("mug")


def test_models_are_strict_and_frozen(full: World) -> None:
    """Models reject unknown fields and cannot be changed after parsing."""
    with pytest.raises(ValidationError):
        Gains(kp=1, ki=2)  # type: ignore[call-arg]
    with pytest.raises(ValidationError):
        full.timestep = 0.01  # type: ignore[misc]


def test_agent_lookup_lists_names(full: World) -> None:
    """World.agent() of an unknown name raises KeyError listing the agents."""
    with pytest.raises(KeyError, match="no agent 'robot_1'; agents: robot_000, can_0"):
        full.agent("robot_1")


# ------------------------------------------------------------------------------------------ the reference


_DOCUMENTED: dict[str, type[BaseModel]] = {
    "world": World, "plugin": PluginConfig, "robot": Robot, "drive": Drive, "lidar": Lidar, "camera": Camera,
    "gripper": Gripper, "arm": Arm, "gains": Gains, "object": Object, "human": Human, "agent": BareAgent,
    "named_pose": NamedPose, "path": WalkPath, "waypoint": Waypoint,
}
_NOT_ATTRIBUTES = {"kind", "lidars", "cameras", "grippers", "arms", "drive", "gains", "plugins", "agents", "source",
                   "config", "line", "column", "positions", "named_poses", "randomize", "path",
                   "waypoints"}
_BOUNDS = (annotated_types.Gt, annotated_types.Ge, annotated_types.Lt, annotated_types.Le)


def _rows(tag: str) -> dict[str, list[str]]:
    """The rows of the attribute table of ``<tag>`` in the reference: attribute -> cells."""
    text = DOCS.read_text(encoding="utf-8")
    section = re.search(rf"^### `<{tag}>`.*?(?=^### |^## |\Z)", text, re.M | re.S)
    assert section is not None, f"no '### `<{tag}>`' section"
    rows = [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in section.group(0).splitlines() if line.startswith("| `")]
    return {row[0].strip("`"): row for row in rows}


def _default(field: FieldInfo) -> str:
    if field.is_required():
        return "required"
    value = field.get_default(call_default_factory=True)
    if isinstance(value, Pose):
        value = value.xyz + value.rpy
    if value is None or value == () or value == "":
        return "none"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, tuple):
        return " ".join(f"{v:g}" for v in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


@pytest.mark.parametrize("tag", list(_DOCUMENTED))
def test_reference_matches_the_models(tag: str) -> None:
    """docs/world-format.md lists exactly each model's attributes, with their defaults, ranges and units."""
    model = _DOCUMENTED[tag]
    rows = _rows(tag)
    assert set(rows) == set(model.model_fields) - _NOT_ATTRIBUTES
    for name, (_, _, unit, default, valid, _) in rows.items():
        field = model.model_fields[name]
        assert default == f"`{_default(field)}`", name
        if any(isinstance(m, _BOUNDS) for m in field.metadata):
            assert f"`{value_range(name, field.metadata, None)}`" in valid, name
            declared = re.search(r"\[([^\]]+)\]", field.description or "")
            assert unit == (declared.group(1) if declared else ""), name
        for choice in literal_values(field.annotation):
            assert f"`{choice}`" in valid, name
