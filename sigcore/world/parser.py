"""World XML -> :class:`~sigcore.world.models.World`, with ``file:line:column`` on every error."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from lxml import etree
from pydantic import BaseModel, ValidationError

from .exceptions import WorldError, WorldIssue
from .locate import SourceMap
from .models import (
    Arm,
    BareAgent,
    Drive,
    Gains,
    Gripper,
    Human,
    Lidar,
    Object,
    PluginConfig,
    Robot,
    World,
)
from .urdf import UrdfError, read_urdf

_AGENTS: dict[str, type[BaseModel]] = {"robot": Robot, "object": Object, "human": Human, "agent": BareAgent}
_ROBOT_CHILDREN: dict[str, tuple[type[BaseModel], str, bool]] = {
    # tag: (model, field of Robot, many)
    "drive": (Drive, "drive", False),
    "lidar": (Lidar, "lidars", True),
    "gripper": (Gripper, "grippers", True),
    "arm": (Arm, "arms", True),
    "gains": (Gains, "gains", False),
}
_INTERNAL_FIELDS = {"kind", "lidars", "grippers", "arms", "drive", "gains", "plugins", "agents", "source", "config",
                    "line"}


class _Reader:
    def __init__(self, path: Path, text: str, root: etree._Element) -> None:
        self.path = path
        self.map = SourceMap(text, root)
        self.issues: list[WorldIssue] = []
        self.locations: dict[tuple[str, str | None], tuple[int, int]] = {}

    def issue(self, element: etree._Element, attribute: str | None, message: str) -> None:
        line, col = self.map.attribute(element, attribute) if attribute else self.map.element(element)
        self.issues.append(WorldIssue(self.path, line, col, str(element.tag), attribute, message))

    def attributes(self, element: etree._Element, model: type[BaseModel]) -> dict[str, Any]:
        fields = set(model.model_fields) - _INTERNAL_FIELDS
        out: dict[str, Any] = {}
        for key, value in element.attrib.items():
            key = str(key)
            if key not in fields:
                self.issue(element, key, f"unknown attribute; valid: {', '.join(sorted(fields))}")
            else:
                out[key] = value
        return out

    def build(self, element: etree._Element, model: type[BaseModel], extra: dict[str, Any]) -> Any:
        """Validate ``element``'s attributes (plus ``extra`` children fields) into ``model``; None on error."""
        data = self.attributes(element, model)
        try:
            return model.model_validate({**data, **extra})
        except ValidationError as e:
            for err in e.errors():
                loc = [str(p) for p in err["loc"]]
                attribute = loc[0] if loc and loc[0] in data else None
                msg = err["msg"].removeprefix("Value error, ")
                if err["type"] == "missing":
                    msg = f"required attribute '{loc[0]}' is missing"
                elif attribute is not None and "got " not in msg:
                    msg = f"{msg} (got {data[attribute]!r})"
                self.issue(element, attribute, msg)
            return None

    def children_of(self, element: etree._Element, allowed: dict[str, Any]) -> list[etree._Element]:
        out = []
        for child in element:
            if not isinstance(child.tag, str):
                continue  # comments, processing instructions
            if child.tag not in allowed:
                self.issue(child, None, f"unknown element inside <{element.tag}>; valid: {', '.join(allowed)}")
            else:
                out.append(child)
        if element.text and element.text.strip():
            self.issue(element, None, f"unexpected text {element.text.strip()[:30]!r}; <{element.tag}> holds "
                                      "only elements")
        return out


def parse_world(path: Path | str, text: str | None = None) -> World:
    """Read and validate a world file.

    Args:
        path: The world file. Relative model paths inside it are resolved against its directory.
        text: The file's content, if already read (``path`` is then only used in messages and for paths).

    Returns:
        The validated world.

    Raises:
        WorldError: with every problem found, each located at ``file:line:column``.
    """
    path = Path(path)
    if text is None:
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            raise WorldError([WorldIssue(path, 1, 1, None, None, f"cannot read world file: {e.strerror}")]) from None
    try:
        root = etree.fromstring(text.encode("utf-8"), parser=etree.XMLParser(resolve_entities=False))
    except etree.XMLSyntaxError as e:
        line, col = e.position
        raise WorldError([WorldIssue(path, line, col, None, None, f"not well-formed XML: {e.msg}")]) from None
    reader = _Reader(path, text, root)
    if root.tag != "world":
        reader.issue(root, None, "the root element must be <world>")
        raise WorldError(reader.issues)
    agents: list[Any] = []
    plugins: list[PluginConfig] = []
    for child in reader.children_of(root, {"plugin": 1, **_AGENTS}):
        if child.tag == "plugin":
            plugin = _plugin(reader, child)
            if plugin is not None:
                plugins.append(plugin)
            continue
        agent = _agent(reader, child, path.parent)
        if agent is not None:
            agents.append((child, agent))
    _check_names(reader, agents, plugins)
    world = reader.build(root, World, {"agents": tuple(a for _, a in agents), "plugins": tuple(plugins),
                                       "source": path})
    if reader.issues or world is None:
        raise WorldError(sorted(reader.issues, key=lambda i: (i.line, i.column)))
    world._locations.update(reader.locations)
    return world


def _plugin(reader: _Reader, element: etree._Element) -> PluginConfig | None:
    reader.children_of(element, {})
    attrs = {str(k): str(v) for k, v in element.attrib.items()}
    name = attrs.pop("name", None)
    if name is None:
        reader.issue(element, None, "required attribute 'name' is missing (the plugin to enable, e.g. 'slam')")
        return None
    line, _ = reader.map.element(element)
    try:
        return PluginConfig(name=name, config=attrs, line=line)
    except ValidationError as e:
        reader.issue(element, "name", e.errors()[0]["msg"] + f" (got {name!r})")
        return None


def _agent(reader: _Reader, element: etree._Element, base: Path) -> Any:
    tag = str(element.tag)
    model = _AGENTS[tag]
    extra: dict[str, Any] = {}
    if tag == "robot":
        many: dict[str, list[Any]] = {"lidars": [], "grippers": [], "arms": []}
        for child in reader.children_of(element, _ROBOT_CHILDREN):
            sub_model, field, is_many = _ROBOT_CHILDREN[str(child.tag)]
            reader.children_of(child, {})
            value = reader.build(child, sub_model, {})
            if value is None:
                continue
            if is_many:
                many[field].append((child, value))
            elif field in extra:
                reader.issue(child, None, f"<{child.tag}> may appear only once in a <robot>")
            else:
                extra[field] = value
        extra.update({k: tuple(v for _, v in items) for k, items in many.items()})
        agent = reader.build(element, model, extra)
        if agent is not None:
            _check_robot(reader, element, agent, many, base)
    else:
        reader.children_of(element, {})
        agent = reader.build(element, model, {})
        if isinstance(agent, Object):
            for attr in ("mesh", "urdf"):
                file = getattr(agent, attr)
                if file is not None and not (base / file).is_file():
                    reader.issue(element, attr, f"file not found: {base / file}")
    if agent is not None:
        reader.locations[(agent.name, None)] = reader.map.element(element)
        if getattr(agent, "controller", None) is not None:
            reader.locations[(agent.name, "controller")] = reader.map.attribute(element, "controller")
    return agent


def _check_robot(reader: _Reader, element: etree._Element, robot: Robot,
                 children: dict[str, list[Any]], base: Path) -> None:
    path = base / robot.urdf
    if not path.is_file():
        reader.issue(element, "urdf", f"file not found: {path}")
        return
    try:
        urdf = read_urdf(path)
    except UrdfError as e:
        reader.issue(element, "urdf", str(e))
        return
    links = set(urdf.links)
    movable = {j.name for j in urdf.movable_joints}
    drive = next((c for c in element if c.tag == "drive"), None)
    if robot.drive is not None and drive is not None:
        for attr in ("left", "right"):
            joint = getattr(robot.drive, attr)
            if joint not in movable:
                reader.issue(drive, attr, f"no movable joint '{joint}' in {robot.urdf}; joints: "
                                          f"{', '.join(sorted(movable))}")
    checks = (("lidars", "link"), ("grippers", "part"), ("arms", "base"), ("arms", "tip"))
    for field, attr in checks:
        for child, value in children[field]:
            link = getattr(value, attr)
            if link not in links:
                reader.issue(child, attr, f"no link '{link}' in {robot.urdf}; links: {', '.join(urdf.links)}")
    _unique(reader, children["lidars"], "name")
    _unique(reader, children["grippers"], "part")
    _unique(reader, children["arms"], "name")


def _unique(reader: _Reader, items: list[Any], attr: str) -> None:
    seen: set[str] = set()
    for child, value in items:
        key = getattr(value, attr)
        if key in seen:
            reader.issue(child, attr, f"duplicate {attr} '{key}'")
        seen.add(key)


def _check_names(reader: _Reader, agents: list[Any], plugins: list[PluginConfig]) -> None:
    seen: dict[str, int] = {}
    for element, agent in agents:
        if agent.name in seen:
            reader.issue(element, "name", f"duplicate name '{agent.name}' (first used on line {seen[agent.name]}); "
                                          "every agent needs its own name")
        else:
            seen[agent.name] = reader.map.element(element)[0]
    names = set()
    for plugin in plugins:
        if plugin.name in names:
            reader.issues.append(WorldIssue(reader.path, plugin.line, 1, "plugin", "name",
                                            f"plugin '{plugin.name}' is enabled twice"))
        names.add(plugin.name)
