"""Worlds with an overflowing number in one attribute: every number attribute of the world models (the package
``sigcore/world/models/`` and ``<randomize>``'s ``sigcore/world/randomization.py``) set to ``1e308``, ``inf`` and
``-1e308`` in turn (issue 28, item 9).

:data:`ATTRIBUTES` lists each attribute with a world that holds it; :func:`generate` writes one world per attribute
and value. ``sigcore check`` must refuse each one at the attribute's ``file:line:column``, naming the attribute and
its valid range, and ``sigcore run`` must refuse it the same way (never a traceback). Which fields are numbers is
read from the models (:func:`number_fields`): a number field added to a model without a row here fails
``test_overflow.py``.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass
from pathlib import Path

from pydantic import BaseModel

from hostile.worlds import SIGBOT
from sigcore.world.models import Pose

VALUES = ("1e308", "inf", "-1e308")
"""The overflowing values tried in every number attribute."""

DRIVE = 'type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"'

# each world holds ``{attr}`` where the attribute goes (``name="value"``); ``{v}`` in a value is the number tried
_FLOOR = '  <object name="floor_box" shape="box" size="1 1 0.1" static="true"/>\n'
_ROBOT = f'  <robot name="r" urdf="{SIGBOT}"{{robot}}>\n    <drive {DRIVE}{{drive}}/>\n{{children}}  </robot>\n'


@dataclass(frozen=True)
class Attribute:
    """One number attribute of one element.

    Attributes:
        model: The model class's name (``Drive``).
        field: The model's field (``max_wheel_velocity``).
        element: The XML element (``drive``).
        attr: The XML attribute (usually the field's name).
        value: The attribute's text, ``{v}`` standing for the number tried (``"0.05 {v}"`` for a range).
    """

    model: str
    field: str
    element: str
    attr: str
    value: str = "{v}"


ATTRIBUTES: tuple[Attribute, ...] = (
    Attribute("World", "timestep", "world", "timestep"),
    Attribute("World", "gravity", "world", "gravity", "0 0 {v}"),
    Attribute("Drive", "radius", "drive", "radius"),
    Attribute("Drive", "separation", "drive", "separation"),
    Attribute("Drive", "max_wheel_velocity", "drive", "max_wheel_velocity"),
    Attribute("Drive", "max_torque", "drive", "max_torque"),
    Attribute("Drive", "cmd_vel_timeout", "drive", "cmd_vel_timeout"),
    Attribute("Lidar", "fov", "lidar", "fov"),
    Attribute("Lidar", "range", "lidar", "range", "0.05 {v}"),
    Attribute("Lidar", "rate", "lidar", "rate"),
    Attribute("Lidar", "noise", "lidar", "noise"),
    Attribute("Camera", "pose", "camera", "pose", "{v} 0 0"),
    Attribute("Camera", "fov", "camera", "fov"),
    Attribute("Camera", "focal", "camera", "focal"),
    Attribute("Camera", "principal", "camera", "principal", "{v} 10"),
    Attribute("Camera", "near", "camera", "near"),
    Attribute("Camera", "far", "camera", "far"),
    Attribute("Camera", "rate", "camera", "rate"),
    Attribute("Camera", "noise", "camera", "noise"),
    Attribute("Gripper", "grasp_radius", "gripper", "grasp_radius"),
    Attribute("Gains", "kp", "gains", "kp"),
    Attribute("Gains", "kv", "gains", "kv"),
    Attribute("Gains", "max_torque", "gains", "max_torque"),
    Attribute("Robot", "pose", "robot", "pose", "{v} 0 0"),
    Attribute("Object", "size", "object", "size", "{v} 1 1"),
    Attribute("Object", "scale", "object_urdf", "scale"),
    Attribute("Object", "mass", "object", "mass"),
    Attribute("Object", "pose", "object", "pose", "0 {v} 0"),
    Attribute("Object", "color", "object", "color", "{v} 0 0 1"),
    Attribute("Object", "friction", "object", "friction"),
    Attribute("Human", "pose", "human", "pose", "0 0 0 0 0 {v}"),
    Attribute("Human", "height", "human", "height"),
    Attribute("Human", "mass", "human", "mass"),
    Attribute("NamedPose", "pose", "named_pose", "pose", "{v} 0 0"),
    Attribute("NamedPose", "bounds", "named_pose", "bounds", "-1 -1 -1 {v} 1 1"),
    Attribute("RandomPose", "region", "random_pose", "region", "-1 -1 {v} 1"),
    Attribute("RandomPose", "z", "random_pose", "z"),
    Attribute("RandomPose", "yaw", "random_pose", "yaw", "-1 {v}"),
    Attribute("RandomPose", "clearance", "random_pose", "clearance"),
    Attribute("Option", "weight", "option", "weight"),
)
"""Every number attribute of the world models, with where it goes (see :func:`world_text`)."""


def _attrs(values: dict[str, str], but: str) -> str:
    """`` a="1" b="2"``: ``values`` as XML attributes, without ``but`` (the attribute under test)."""
    return "".join(f' {k}="{v}"' for k, v in values.items() if k != but)


def world_text(attribute: Attribute, number: str) -> tuple[str, str]:
    """A world file whose only problem can be ``attribute`` set with ``number``, and the text that starts that
    attribute in it (``attr="``), so that its line and column can be found.

    Raises:
        KeyError: an element this function does not know.
    """
    setting = f'{attribute.attr}="{attribute.value.format(v=number)}"'
    extra = f" {setting}"
    robot = drive = children = ""
    world_attrs = 'name="overflow"'
    body = _FLOOR
    element = attribute.element
    if element == "world":
        world_attrs += extra
    elif element == "drive":
        drive = extra
    elif element == "robot":
        robot = extra
    elif element == "lidar":
        children = f'    <lidar name="scan" link="base_laser_link"{extra}/>\n'
    elif element == "camera":
        children = f'    <camera name="eye" link="head_camera_link"{extra}/>\n'
    elif element == "gripper":
        children = f'    <gripper part="l_hand_link"{extra}/>\n'
    elif element == "gains":
        children = f"    <gains{extra}/>\n"
    elif element == "object":
        own = _attrs({"size": "0.1 0.1 0.1", "pose": "1 0 0.5"}, attribute.attr)
        body += f'  <object name="thing" shape="box"{own}{extra}/>\n'
    elif element == "object_urdf":
        body += f'  <object name="thing" urdf="{SIGBOT}" pose="2 0 0"{extra}/>\n'
    elif element == "human":
        body += f'  <human name="person"{_attrs({"pose": "0 2 0"}, attribute.attr)}{extra}/>\n'
    elif element == "named_pose":
        pose = "" if attribute.attr == "pose" else ' pose="1 1 0"'
        body += f'  <named_pose name="spot"{pose}{extra}/>\n'
    elif element == "random_pose":
        region = "" if attribute.attr == "region" else ' region="-1 -1 1 1"'
        body += (f'  <object name="thing" shape="box" size="0.1 0.1 0.1" pose="1 0 0.5"/>\n  <randomize>\n'
                 f'    <pose entity="thing"{region}{extra}/>\n  </randomize>\n')
    elif element == "option":
        body += ('  <object name="thing" shape="box" size="0.1 0.1 0.1" pose="1 0 0.5"/>\n  <randomize>\n'
                 f'    <choose entity="thing">\n      <option color="1 0 0 1"{extra}/>\n'
                 '      <option color="0 1 0 1"/>\n    </choose>\n  </randomize>\n')
    else:
        raise KeyError(element)
    robot_text = _ROBOT.format(robot=robot, drive=drive, children=children)
    if element == "drive" and f' {attribute.attr}="' in f" {DRIVE}":  # replace the drive's own value
        start = robot_text.index(f' {attribute.attr}="')
        end = robot_text.index('"', start + len(attribute.attr) + 3) + 1
        robot_text = robot_text[:start] + robot_text[end:]
    return f"<world {world_attrs}>\n{body}{robot_text}</world>\n", f'{attribute.attr}="'


_START = {"world": "<world", "drive": "<drive", "robot": "<robot", "lidar": "<lidar", "camera": "<camera",
          "gripper": "<gripper", "gains": "<gains", "object": '<object name="thing"',
          "object_urdf": '<object name="thing"', "human": "<human", "named_pose": "<named_pose",
          "random_pose": "<pose ", "option": "<option "}
"""Where each element starts in :func:`world_text`'s world (its attribute is the first after it)."""


@dataclass(frozen=True)
class OverflowCase:
    """One world: ``attribute`` set with ``number``; the message must name ``path:line:column``."""

    name: str
    path: Path
    attribute: Attribute
    number: str
    line: int
    column: int


def generate(directory: Path) -> list[OverflowCase]:
    """Write one world per attribute of :data:`ATTRIBUTES` and value of :data:`VALUES` into ``directory``."""
    directory.mkdir(parents=True, exist_ok=True)
    cases = []
    for attribute in ATTRIBUTES:
        for number in VALUES:
            text, marker = world_text(attribute, number)
            offset = text.index(marker, text.index(_START[attribute.element]))
            line = text.count("\n", 0, offset) + 1
            column = offset - (text.rfind("\n", 0, offset) + 1) + 1
            name = f"{attribute.model}_{attribute.field}_{number.replace('-', 'minus_').replace('+', '')}"
            path = directory / f"{name}.xml"
            path.write_text(text, encoding="utf-8")
            cases.append(OverflowCase(name, path, attribute, number, line, column))
    return cases


def number_fields(model: type[BaseModel]) -> list[str]:
    """The fields of ``model`` that hold numbers (a float, a tuple of them or a pose, optional or not)."""

    def numeric(annotation: object) -> bool:
        if annotation is float:
            return True
        if annotation is Pose:  # an attribute "x y z roll pitch yaw" (child elements are models of their own)
            return True
        return any(numeric(a) for a in typing.get_args(annotation))

    return [name for name, info in model.model_fields.items() if numeric(info.annotation)]


AT_LIMIT: dict[tuple[str, str], str] = {
    ("Drive", "max_wheel_velocity"): "1000",
    ("Drive", "max_torque"): "100000",
    ("Lidar", "range"): "1000",
    ("Camera", "pose"): "10000",
    ("Gains", "kp"): "100000",
    ("Gains", "kv"): "10000",
    ("Gains", "max_torque"): "100000",
    ("Robot", "pose"): "-10000",
    ("Object", "size"): "1000",
    ("Object", "pose"): "10000",
    ("Human", "pose"): "-100",
    ("NamedPose", "pose"): "10000",
    ("NamedPose", "bounds"): "10000",
    ("RandomPose", "region"): "10000",
    ("RandomPose", "z"): "-10000",
    ("RandomPose", "yaw"): "100",
}
"""The attributes that took ``1e308`` before they were bounded, each with its largest valid number (the number
:data:`ATTRIBUTES` puts in its value): a world at the limit must still pass ``check`` and run."""


def generate_at_limit(directory: Path) -> list[Path]:
    """Write one world per :data:`AT_LIMIT` entry into ``directory``, the attribute at its limit."""
    directory.mkdir(parents=True, exist_ok=True)
    by_key = {(a.model, a.field): a for a in ATTRIBUTES}
    paths = []
    for key, number in AT_LIMIT.items():
        text, _ = world_text(by_key[key], number)
        path = directory / f"{key[0]}_{key[1]}_limit.xml"
        path.write_text(text, encoding="utf-8")
        paths.append(path)
    return paths
