"""World XML -> :class:`~sigcore.world.models.World`, with ``file:line:column`` on every error."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

from lxml import etree
from pydantic import BaseModel, ValidationError

from .exceptions import UrdfError, WorldError, WorldIssue
from .meshes import mesh_problem
from .messages import error_field, message, unknown
from .models import (
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
    Robot,
    WalkPath,
    Waypoint,
    World,
    start_pose_name,
)
from .randomization import Choice, Option, Randomize, RandomPose, with_option
from .reader import INTERNAL_FIELDS, Reader
from .urdf import UrdfModel, resolve_mesh

_AGENTS: dict[str, type[BaseModel]] = {"robot": Robot, "object": Object, "human": Human, "agent": BareAgent}
_ROBOT_CHILDREN: dict[str, tuple[type[BaseModel], str, bool]] = {
    # tag: (model, field of Robot, many)
    "drive": (Drive, "drive", False),
    "lidar": (Lidar, "lidars", True),
    "camera": (Camera, "cameras", True),
    "gripper": (Gripper, "grippers", True),
    "arm": (Arm, "arms", True),
    "gains": (Gains, "gains", False),
}
_LIBXML_POSITION = re.compile(r", line \d+, column \d+$")


def parse_world(path: Path | str, text: str | None = None) -> World:
    """Read and validate a world file.

    Args:
        path: The world file. Relative model paths inside it are resolved against its directory.
        text: The file's content, if already read (``path`` is then only used in messages and for paths).

    Returns:
        The validated world.

    Raises:
        WorldError: with every problem found, each located at ``file:line:column``, sorted by line.
    """
    path = Path(path)
    if text is None:
        text = _read(path)
    try:
        root = etree.fromstring(text.encode("utf-8"), parser=etree.XMLParser(resolve_entities=False))
    except etree.XMLSyntaxError as e:
        line, col = e.position
        msg = _LIBXML_POSITION.sub("", str(e.msg))
        raise WorldError([WorldIssue(path, line, col, None, None, f"not well-formed XML: {msg}")]) from None
    reader = Reader(path, text, root)
    doctype = root.getroottree().docinfo
    if doctype.doctype or doctype.internalDTD is not None:
        line = text.count("\n", 0, max(text.find("<!DOCTYPE"), 0)) + 1
        column = max(text.find("<!DOCTYPE"), 0) - (text.rfind("\n", 0, max(text.find("<!DOCTYPE"), 0)) + 1) + 1
        raise WorldError([WorldIssue(path, line, column, None, None, "a <!DOCTYPE> declaration is not part of the "
                                     "world format (entities and DTDs are never loaded); remove it")])
    if root.tag != "world":
        reader.issue(root, None, f"the root element is <{root.tag}>; valid: <world>")
        raise WorldError(reader.issues)
    agents: list[Any] = []
    plugins: list[Any] = []
    poses: list[Any] = []
    randomizers: list[etree._Element] = []
    for child in reader.children_of(root, {"plugin": 1, "named_pose": 1, **_AGENTS, "randomize": 1}):
        if child.tag == "randomize":
            randomizers.append(child)
            continue
        if child.tag == "named_pose":
            reader.children_of(child, {})
            pose = reader.build(child, NamedPose, {})
            if pose is not None:
                poses.append((child, pose))
            continue
        if child.tag == "plugin":
            plugin = _plugin(reader, child)
            if plugin is not None:
                plugins.append((child, plugin))
            continue
        agent = _agent(reader, child, path.parent)
        if agent is not None:
            agents.append((child, agent))
    _unique(reader, agents, "name", "every agent needs its own name")
    _unique(reader, plugins, "name", "enable a plugin once")
    _unique(reader, poses, "name", "every named pose needs its own name")
    _automatic_poses(reader, poses, [a for _, a in agents])
    randomize = _randomize(reader, randomizers, agents, path.parent)
    world = reader.build(root, World, {"agents": tuple(a for _, a in agents),
                                       "plugins": tuple(p for _, p in plugins),
                                       "named_poses": tuple(p for _, p in poses), "randomize": randomize,
                                       "source": path})
    if reader.issues or world is None:
        raise WorldError(sorted(reader.issues, key=lambda i: (i.line, i.column)))
    reader.locations[("", None)] = reader.map.element(root)  # the <world> element (World.location(""))
    world.record_locations(reader.locations)
    world.share_urdfs(reader.urdfs)
    if world.randomize is not None:  # against the world: names, surfaces, areas, bounds (before any seed)
        from .randomize import check

        issues = check(world)
        if issues:
            raise WorldError(sorted(issues, key=lambda i: (i.line, i.column)))
    return world


def _read(path: Path) -> str:
    try:
        data = path.read_bytes()
    except OSError as e:
        issue = WorldIssue(path, 1, 1, None, None, f"cannot read world file: {e.strerror}")
        raise WorldError([issue]) from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise WorldError([WorldIssue(path, line, col, None, None, f"byte 0x{data[e.start]:02x} is not UTF-8; "
                                     "valid: a file saved as UTF-8")]) from None


def _plugin(reader: Reader, element: etree._Element) -> PluginConfig | None:
    reader.children_of(element, {})
    attrs = {str(k): str(v) for k, v in element.attrib.items()}
    name = attrs.pop("name", None)
    if name is None:
        reader.issue(element, None, "required attribute 'name' is missing (the plugin to enable, "
                                    "e.g. 'slam')")
        return None
    try:
        line, column = reader.map.element(element)
        positions = {str(k): reader.map.attribute(element, str(k)) for k in element.attrib}
        return PluginConfig(name=name, config=attrs, line=line, column=column, positions=positions)
    except ValidationError as e:
        for err in e.errors():
            reader.issue(element, "name", message(PluginConfig, err, name))
        return None


def _agent(reader: Reader, element: etree._Element, base: Path) -> Any:
    tag = str(element.tag)
    model = _AGENTS[tag]
    extra: dict[str, Any] = {}
    children: dict[str, list[Any]] = {"drive": [], "lidars": [], "cameras": [], "grippers": [], "arms": [], "gains": []}
    if tag == "robot":
        first: dict[str, etree._Element] = {}
        for child in reader.children_of(element, _ROBOT_CHILDREN):
            sub_model, field, is_many = _ROBOT_CHILDREN[str(child.tag)]
            reader.children_of(child, {})
            if not is_many and field in first:
                reader.issue(child, None, f"<{child.tag}> may appear only once in a <robot> (first on line "
                                          f"{reader.line(first[field])})")
                continue
            first[field] = child
            value = reader.build(child, sub_model, {})
            if value is not None:
                children[field].append((child, value))
        for field, items in children.items():
            values = tuple(v for _, v in items)
            if field in ("lidars", "cameras", "grippers", "arms"):
                extra[field] = values
            elif values:
                extra[field] = values[0]
    elif tag == "human":
        paths = reader.children_of(element, {"path": 1})
        for extra_path in paths[1:]:
            reader.issue(extra_path, None, f"<path> may appear only once in a <human> (first on line "
                                           f"{reader.line(paths[0])})")
        if paths:
            path = _path(reader, paths[0])
            if path is not None:
                extra["path"] = path
    else:
        reader.children_of(element, {})
    agent = reader.build(element, model, extra)
    if tag in ("robot", "object"):
        _check_files(reader, element, base, children)
    _unique(reader, children["lidars"], "name", "each lidar of a robot needs its own name")
    _unique(reader, children["cameras"], "name", "each camera of a robot needs its own name")
    _unique(reader, children["grippers"], "part", "one gripper per part")
    _unique(reader, children["arms"], "name", "each arm of a robot needs its own name")
    if agent is not None:
        reader.locations[(agent.name, None)] = reader.map.element(element)
        for key in element.attrib:
            reader.locations[(agent.name, str(key))] = reader.map.attribute(element, str(key))
        for child, _ in children["drive"]:
            reader.locations[(agent.name, "drive")] = reader.map.element(child)
        for field, tag in (("lidars", "lidar"), ("cameras", "camera"), ("arms", "arm")):
            for child, value in children[field]:
                reader.locations[(agent.name, f"{tag}:{value.name}")] = reader.map.attribute(child, "name")
        if isinstance(agent, Human) and agent.path is not None:
            path_element = element.find("path")
            reader.locations[(agent.name, "path")] = reader.map.element(path_element)
            for i, point in enumerate(path_element.findall("waypoint")):
                reader.locations[(agent.name, f"waypoint:{i}")] = reader.map.element(point)
                for key in point.attrib:
                    reader.locations[(agent.name, f"waypoint:{i}:{key}")] = reader.map.attribute(point, str(key))
    return agent


def _path(reader: Reader, element: etree._Element) -> WalkPath | None:
    """A ``<path>`` and its ``<waypoint>`` children; None (reported) on error."""
    points = reader.children_of(element, {"waypoint": 1})
    waypoints = []
    for point in points:
        reader.children_of(point, {})
        waypoint = reader.build(point, Waypoint, {})
        if waypoint is not None:
            waypoints.append(waypoint)
    if not points:
        reader.issue(element, None, "a <path> with no points; valid: one or more <waypoint x=\"..\" y=\"..\"/> "
                                    "inside it, walked in order")
        return None
    # a waypoint with errors was reported: the path's own attributes are still checked, on a stand-in
    path: WalkPath | None = reader.build(element, WalkPath, {"waypoints": tuple(waypoints) or (Waypoint(x=0, y=0),)})
    return path if len(waypoints) == len(points) else None


def _located(reader: Reader, element: etree._Element) -> dict[str, Any]:
    """Where ``element`` and each of its attributes are: the ``line``, ``column`` and ``positions`` fields."""
    line, column = reader.map.element(element)
    return {"line": line, "column": column,
            "positions": {str(k): reader.map.attribute(element, str(k)) for k in element.attrib}}


def _randomize(reader: Reader, elements: list[etree._Element], agents: list[Any], base: Path) -> Randomize | None:
    """The ``<randomize>`` element (at most one) as a model; its ``<choose>`` options validated against their
    object. What needs the whole world (names, surfaces, bounds) is :func:`sigcore.world.randomize.check`'s."""
    if not elements:
        return None
    for extra in elements[1:]:
        reader.issue(extra, None, f"<randomize> may appear only once in a <world> (first on line "
                                  f"{reader.line(elements[0])})")
    element = elements[0]
    built = {agent.name: child for child, agent in agents}
    poses: list[RandomPose] = []
    choices: list[Choice] = []
    for child in reader.children_of(element, {"pose": 1, "choose": 1}):
        if child.tag == "pose":
            reader.children_of(child, {})
            pose = reader.build(child, RandomPose, _located(reader, child))
            if pose is not None:
                poses.append(pose)
            continue
        target = built.get(str(child.get("entity", "")).strip())
        if child.get("entity") is not None and (target is None or target.tag != "object"):
            name = str(child.get("entity")).strip()
            objects = [n for n, e in built.items() if e.tag == "object"]
            what = f"'{name}' is a <{target.tag}>" if target is not None else f"no object '{name}'"
            reader.issue(child, "entity", f"{what}; <choose> picks among variants of an <object>; valid: "
                                          f"{', '.join(objects) or 'none'}")
            target = None
        option_elements = reader.children_of(child, {"option": 1})
        options = [o for o in (_option(reader, e, target, base) for e in option_elements) if o is not None]
        # an option with errors was reported: the <choose>'s own attributes are still checked, on a stand-in
        stand_in = (Option(),) if len(options) < len(option_elements) else ()
        choice = reader.build(child, Choice, {"options": tuple(options) or stand_in, **_located(reader, child)})
        if choice is not None and not stand_in:
            choices.append(choice)
    return reader.build(element, Randomize, {"poses": tuple(poses), "choices": tuple(choices),
                                             **_located(reader, element)})


def _option(reader: Reader, element: etree._Element, target: etree._Element | None, base: Path) -> Option | None:
    """One ``<option>``: its object attributes checked as the object ``target`` would take them (errors at the
    option's line), its ``urdf``/``mesh`` files as an object's."""
    reader.children_of(element, {})
    valid = sorted((set(Object.model_fields) - INTERNAL_FIELDS - {"name"}) | {"weight"})
    attributes: dict[str, str] = {}
    own: dict[str, Any] = {}
    for key, value in element.attrib.items():
        key = str(key)
        if key == "weight":
            own[key] = str(value)
        elif key == "name":
            reader.issue(element, key, "an option cannot rename its object; valid: " + ", ".join(valid))
        elif key not in valid:
            reader.issue(element, key, unknown("attribute", key, valid))
        else:
            attributes[key] = str(value)
    if target is not None:
        merged = with_option({str(k): str(v) for k, v in target.attrib.items()}, attributes)
        try:
            Object.model_validate(merged)
        except ValidationError as e:
            for err in e.errors():
                field = error_field(err)
                raw = merged.get(field) if field else None
                text = message(Object, err, raw if isinstance(raw, str) else None)
                if field in attributes:
                    reader.issue(element, field, text)
                else:
                    reader.issue(element, None, f"<object name='{target.get('name')}'> with this option: {text}")
    _check_files(reader, element, base, {})
    try:
        return Option(attributes=attributes, **own, **_located(reader, element))
    except ValidationError as e:
        for err in e.errors():
            reader.issue(element, "weight", message(Option, err, own.get("weight")))
        return None


def _check_files(reader: Reader, element: etree._Element, base: Path,
                 children: dict[str, list[Any]]) -> None:
    """Check that ``urdf``/``mesh`` files exist, that a URDF reads, and the names a robot takes from it."""
    for attr in ("urdf",) if element.tag == "robot" else ("urdf", "mesh"):
        raw = element.get(attr)
        if raw is None:
            continue
        if not raw.strip():
            reader.issue(element, attr, "empty path; valid: a file path, relative to the world file's "
                                        "directory")
            continue
        too_long = _path_too_long(raw.strip())
        if too_long:
            reader.issue(element, attr, too_long)
            continue
        file = Path(os.path.normpath(base / raw.strip()))
        problem = mesh_problem(file) if attr == "mesh" and file.is_file() else None
        if problem is not None:
            reader.issue(element, attr, f"mesh file {file}: {problem}; valid: an .stl or .obj mesh")
        elif not file.is_file():
            relative = "" if Path(raw.strip()).is_absolute() else \
                " (relative paths start at the world file's directory)"
            reader.issue(element, attr, f"file not found: {file}{relative}")
        elif attr == "urdf":
            try:
                document = reader.urdfs.get(file)
                urdf = document.model
            except UrdfError as e:
                reader.issue(element, attr, f"invalid URDF: {e}")
                continue
            broken = _urdf_mesh_problem(document.root, file)
            if broken is not None:
                reader.issue(element, attr, f"invalid URDF: {broken}")
                continue
            floating = [j.name for j in urdf.joints if j.type == "floating"]
            if floating:
                reader.issue(element, attr, f"unsupported URDF: joint '{floating[0]}' of {file} is floating, which "
                                            "the backends cannot simulate inside a model (MuJoCo refuses it, "
                                            "PyBullet makes it fixed); valid joint types: revolute, continuous, "
                                            "prismatic, fixed, planar")
                continue
            if element.tag == "robot":
                _check_robot(reader, urdf, raw.strip(), children)


def _urdf_mesh_problem(root: etree._Element, file: Path) -> str | None:
    """``file:line: mesh ...: problem`` for the first mesh of a URDF that exists and is broken (missing meshes are
    the backend's to report, with the link)."""
    seen: set[Path] = set()
    for mesh in root.iter("mesh"):
        path = resolve_mesh(str(mesh.get("filename", "")), file.parent)
        if path is None or path in seen:
            continue
        seen.add(path)
        problem = mesh_problem(path)
        if problem is not None:
            return f"{file}:{mesh.sourceline}: mesh {path}: {problem}"
    return None


MAX_PATH = 1024
"""Longest ``urdf``/``mesh`` path in a world file [characters]; each '/'-separated part at most 255 (NAME_MAX)."""


def _path_too_long(raw: str) -> str | None:
    """Why the path ``raw`` is too long for the file system, or None."""
    if len(raw) > MAX_PATH:
        return f"path of {len(raw)} characters; valid: at most {MAX_PATH}"
    part = max(raw.replace("\\", "/").split("/"), key=len)
    if len(part.encode("utf-8")) > 255:
        return f"path part of {len(part.encode('utf-8'))} bytes ({part[:20]!r}...); valid: at most 255 per part"
    return None


def _check_robot(reader: Reader, urdf: UrdfModel, file: str, children: dict[str, list[Any]]) -> None:
    """Check the names that a robot's child elements take from its URDF."""
    movable = sorted(j.name for j in urdf.movable_joints)
    for child, drive in children["drive"]:
        for attr in ("left", "right"):
            joint = getattr(drive, attr)
            if joint not in movable:
                reader.issue(child, attr, f"no movable joint '{joint}' in {file}; "
                                          f"valid: {', '.join(movable)}")
        unknown_casters = [link for link in drive.casters or () if link not in urdf.links]
        if unknown_casters:
            reader.issue(child, "casters", f"no link {', '.join(repr(c) for c in unknown_casters)} in {file}; "
                                           f"valid: space-separated links among {', '.join(urdf.links)}")
    checks = (("lidars", "link"), ("cameras", "link"), ("grippers", "part"), ("arms", "base"), ("arms", "tip"))
    for field, attr in checks:
        for child, value in children[field]:
            link = getattr(value, attr)
            if link not in urdf.links:
                reader.issue(child, attr, f"no link '{link}' in {file}; valid: {', '.join(urdf.links)}")
    for child, camera in children["cameras"]:
        for frame in (camera.link_frame, camera.optical_frame):
            if frame in urdf.links:
                reader.issue(child, "name", f"camera '{camera.name}' would add the frame '{frame}', which is a link "
                                            f"of {file}; valid: a name whose frames '<name>_link' and "
                                            "'<name>_optical_frame' are not links")


def _automatic_poses(reader: Reader, poses: list[Any], agents: list[Any]) -> None:
    """Report every named pose that takes the name of a robot's automatic start pose."""
    starts = {start_pose_name(a.name): a.name for a in agents if isinstance(a, Robot)}
    for element, pose in poses:
        if pose.name in starts:
            reader.issue(element, "name", f"'{pose.name}' is the automatic start pose of robot "
                                          f"'{starts[pose.name]}'; valid: another name")


def _unique(reader: Reader, items: list[Any], attr: str, rule: str) -> None:
    """Report every item whose ``attr`` repeats an earlier one's, pointing at the first."""
    first: dict[str, etree._Element] = {}
    for element, value in items:
        key = getattr(value, attr)
        if key in first:
            line = reader.line(first[key])
            reader.issue(element, attr, f"duplicate {attr} '{key}' (first on line {line}); {rule}")
        else:
            first[key] = element
