"""URDF files read once per world: the parsed document shared by everyone, and its link and joint names.

:class:`UrdfDocument` holds a file's text and parsed tree (read once; users that rewrite it take a copy), and
:class:`UrdfModel`, the names and kinematic tree the core checks requests against. :class:`UrdfFiles` is a
world's set of documents, one per file (``World.urdf``); the backends and features take the document from there
instead of reading the file again.
"""

from __future__ import annotations

import copy
import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
from lxml import etree

from .exceptions import UrdfError
from .limits import parse_floats

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")


@dataclass(frozen=True)
class UrdfJoint:
    """One ``<joint>`` of a URDF."""

    name: str
    type: str
    parent: str
    child: str
    lower: float | None = None
    upper: float | None = None
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    origin_xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """``<origin xyz>``: the child link's frame in the parent's at angle 0 [m]."""
    origin_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """``<origin rpy>``: its fixed-axis roll, pitch, yaw [rad]."""

    @property
    def movable(self) -> bool:
        """Revolute, continuous or prismatic (one degree of freedom)."""
        return self.type in ("revolute", "continuous", "prismatic")


@dataclass(frozen=True)
class UrdfModel:
    """Names and tree of a URDF robot."""

    name: str
    links: tuple[str, ...]
    joints: tuple[UrdfJoint, ...]
    root: str
    meshes: tuple[str, ...] = field(default=())

    @property
    def movable_joints(self) -> tuple[UrdfJoint, ...]:
        """Joints with one degree of freedom, in file order."""
        return tuple(j for j in self.joints if j.movable)

    def link_pose(self, link: str, angles: Mapping[str, float], xyz: Sequence[float],
                  wxyz: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """The pose ``(xyz, wxyz)`` of ``link`` when the root link is at ``(xyz, wxyz)`` and the movable joints at
        ``angles`` [rad] (revolute and continuous: a rotation about the axis after the joint's ``<origin>``; others
        at 0), as robot_state_publisher composes it. Raises ``KeyError`` for an unknown link."""
        from ..geometry import quat_from_axis_angle, quat_from_rpy, quat_mul, quat_rotate

        by_child = {j.child: j for j in self.joints}
        chain = []
        while link != self.root:
            joint = by_child[link]
            chain.append(joint)
            link = joint.parent
        pos, quat = np.asarray(xyz, dtype=float), np.asarray(wxyz, dtype=float)
        for joint in reversed(chain):
            pos = pos + quat_rotate(quat, np.array(joint.origin_xyz))
            quat = quat_mul(quat, quat_from_rpy(*joint.origin_rpy))
            if joint.type in ("revolute", "continuous") and joint.name in angles:
                quat = quat_mul(quat, quat_from_axis_angle(np.array(joint.axis), angles[joint.name]))
        return pos, quat

    def joint(self, name: str) -> UrdfJoint:
        """The joint called ``name``; ``KeyError`` listing the valid names otherwise."""
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(f"no joint '{name}'; joints: {', '.join(j.name for j in self.movable_joints)}")


PARSER_OPTIONS: dict[str, bool] = {"resolve_entities": False, "no_network": True}
"""lxml parser settings for URDF files: no entity expansion, no network access."""


@dataclass(frozen=True, eq=False)
class UrdfDocument:
    """One URDF file, read and parsed once and shared by the core, the backends and the features.

    Make one with :meth:`read`; a world hands them out with :meth:`sigcore.world.World.urdf`.

    Attributes:
        path: The file, as it was asked for (normalised).
        text: Its content, decoded with the encoding its XML declaration names (UTF-8 if none).
    """

    path: Path
    text: str
    _root: etree._Element = field(repr=False)

    @classmethod
    def read(cls, path: Path) -> UrdfDocument:
        """Read and parse the URDF file at ``path`` (no entity expansion, no network).

        Raises:
            UrdfError: the file cannot be read or is not XML.
        """
        try:
            data = path.read_bytes()
        except OSError as err:
            raise UrdfError(path, 0, f"cannot read: {err}") from None
        try:
            root = etree.fromstring(data, etree.XMLParser(**PARSER_OPTIONS), base_url=str(path))
        except etree.XMLSyntaxError as err:
            msg = re.sub(r", line \d+, column \d+$", "", str(err.msg))
            raise UrdfError(path, err.lineno or 0, f"not valid XML: {msg}") from None
        encoding = root.getroottree().docinfo.encoding or "utf-8"
        try:
            text = data.decode("utf-8-sig" if encoding.lower() in ("utf-8", "utf8") else encoding)
        except (LookupError, UnicodeDecodeError) as err:
            raise UrdfError(path, 0, f"cannot decode as {encoding}: {err}") from None
        return cls(path, text, root)

    @classmethod
    def generated(cls, path: Path, text: str) -> UrdfDocument:
        """A document sigcore wrote itself (a person's body, :mod:`sigcore.world.body`), named ``path`` in
        messages (no file is read)."""
        return cls(path, text, etree.fromstring(text.encode(), etree.XMLParser(**PARSER_OPTIONS)))

    @property
    def root(self) -> etree._Element:
        """The parsed ``<robot>`` element, shared by every user: read it, never change it (see
        :meth:`copy_root`)."""
        return self._root

    def copy_root(self) -> etree._Element:
        """A deep copy of :attr:`root`, for a user that rewrites the URDF (e.g. a backend resolving meshes)."""
        return copy.deepcopy(self._root)

    @cached_property
    def model(self) -> UrdfModel:
        """The link and joint names and the kinematic tree (checked on first use).

        Raises:
            UrdfError: the root is not ``<robot>``, or the links and joints are not one consistent tree.
        """
        return _names(self.path, self._root)


class UrdfFiles:
    """The URDF documents of one world, by file: each file is read and parsed on first use, then shared."""

    def __init__(self) -> None:
        self._documents: dict[Path, UrdfDocument] = {}
        self._generated: dict[tuple[object, ...], UrdfDocument] = {}

    def get(self, path: Path) -> UrdfDocument:
        """The document of the file at ``path``, read now if it was not read before.

        Raises:
            UrdfError: the file cannot be read or is not XML (not remembered: a later call tries again).
        """
        key = Path(os.path.abspath(path))
        document = self._documents.get(key)
        if document is None:
            document = self._documents[key] = UrdfDocument.read(Path(os.path.normpath(path)))
        return document

    def generated(self, key: tuple[object, ...], path: Path, write: Callable[[], str]) -> UrdfDocument:
        """The generated document for ``key`` (written by ``write`` on first use, then shared)."""
        document = self._generated.get(key)
        if document is None:
            document = self._generated[key] = UrdfDocument.generated(path, write())
        return document

    @property
    def paths(self) -> tuple[Path, ...]:
        """The files read so far (absolute), in the order they were read."""
        return tuple(self._documents)

    def __eq__(self, other: object) -> bool:
        """Always equal to another ``UrdfFiles``: a cache of file contents does not tell two worlds apart."""
        return isinstance(other, UrdfFiles)

    __hash__ = None  # type: ignore[assignment]  # mutable container: not hashable


def read_urdf(path: Path) -> UrdfModel:
    """Read link and joint names from the URDF file at ``path`` (a world shares them: :meth:`World.urdf`).

    Raises:
        UrdfError: the file is missing, not XML, or not a consistent tree.
    """
    return UrdfDocument.read(path).model


def _names(path: Path, root: etree._Element) -> UrdfModel:
    """The names model of the parsed URDF ``root`` read from ``path``; ``UrdfError`` if it is inconsistent."""
    if root.tag != "robot":
        raise UrdfError(path, root.sourceline or 0, f"root element is <{root.tag}>, expected <robot>")
    link_elements = root.findall("link")
    links = tuple(str(e.get("name")) for e in link_elements)
    if not links:
        raise UrdfError(path, root.sourceline or 0, "no <link> in the robot")
    if len(links) > MAX_LINKS:
        raise UrdfError(path, link_elements[MAX_LINKS].sourceline or 0,
                        f"{len(links)} links; the limit is {MAX_LINKS} links per URDF (sigcore.world.urdf.MAX_LINKS)")
    _unique_names(path, link_elements, "link")
    _unique_names(path, root.findall("joint"), "joint")
    for element in link_elements:
        _check_link(path, element)
    joints: list[UrdfJoint] = []
    for e in root.findall("joint"):
        parent, child = e.find("parent"), e.find("child")
        jtype = e.get("type", "")
        if jtype not in JOINT_TYPES:
            raise UrdfError(path, e.sourceline or 0, f"joint '{e.get('name')}' has type '{jtype}', which sigcore "
                                                     f"does not support; valid: {', '.join(JOINT_TYPES)}")
        if parent is None or child is None:
            raise UrdfError(path, e.sourceline or 0, f"joint '{e.get('name')}' needs <parent> and <child>")
        limit = e.find("limit")
        lower = upper = None
        if limit is not None and jtype in ("revolute", "prismatic"):
            try:
                lower, upper = float(limit.get("lower", "0")), float(limit.get("upper", "0"))
            except ValueError:
                raise UrdfError(path, limit.sourceline or 0,
                                f"joint '{e.get('name')}': <limit lower upper> must be numbers") from None
        axis_el = e.find("axis")
        try:
            xyz = axis_el.get("xyz", "1 0 0") if axis_el is not None else "1 0 0"
            axis = tuple(float(v) for v in xyz.split())
        except ValueError:
            axis = ()
        if len(axis) != 3:
            raise UrdfError(path, e.sourceline or 0, f"joint '{e.get('name')}': <axis xyz> needs 3 numbers")
        origin = e.find("origin")
        xyz, rpy = (_joint_origin(path, e, origin, attribute) for attribute in ("xyz", "rpy"))
        joint = UrdfJoint(str(e.get("name")), jtype, str(parent.get("link")), str(child.get("link")), lower,
                          upper, (axis[0], axis[1], axis[2]), xyz, rpy)
        for link in (joint.parent, joint.child):
            if link not in links:
                raise UrdfError(path, e.sourceline or 0, f"joint '{joint.name}' names unknown link '{link}'")
        joints.append(joint)
    children = {j.child for j in joints}
    roots = [link for link in links if link not in children]
    if len(roots) != 1:
        raise UrdfError(path, root.sourceline or 0, f"expected one root link, found {roots}")
    meshes = tuple(str(m.get("filename")) for m in root.iter("mesh"))
    return UrdfModel(str(root.get("name", path.stem)), links, tuple(joints), roots[0], meshes)


def _joint_origin(path: Path, joint: etree._Element, origin: etree._Element | None,
                  attribute: str) -> tuple[float, float, float]:
    """``<origin xyz>`` or ``<origin rpy>`` of ``joint`` (zeros if absent); ``UrdfError`` unless 3 finite numbers."""
    text = origin.get(attribute) if origin is not None else None
    if text is None:
        return (0.0, 0.0, 0.0)
    try:
        values = parse_floats(text, 3)
    except ValueError:
        assert origin is not None
        raise UrdfError(path, origin.sourceline or 0, f"joint '{joint.get('name')}': <origin {attribute}="
                                                      f"{text[:40]!r}> needs 3 finite numbers") from None
    return (values[0], values[1], values[2])


MAX_LINKS = 500
"""Most links in one URDF (so the longest kinematic chain); a larger model is refused when the world is read."""

_NUMBERS = {"mass": ("value",), "inertia": ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), "origin": ("xyz", "rpy")}


def _unique_names(path: Path, elements: list[etree._Element], what: str) -> None:
    """``UrdfError`` at the second ``<what>`` of any name, pointing at the first."""
    first: dict[str, int] = {}
    for e in elements:
        name = str(e.get("name"))
        if name in first:
            raise UrdfError(path, e.sourceline or 0, f"duplicate {what} name '{name}' (first on line {first[name]}); "
                                                     f"every {what} needs its own name")
        first[name] = e.sourceline or 0


def _check_link(path: Path, link: etree._Element) -> None:
    """``UrdfError`` for a link whose ``<inertial>`` or ``<origin>`` numbers are not finite, or whose mass or
    principal moments of inertia are negative; geometry scales must be finite and > 0."""
    name = link.get("name")
    for e in link.iter("mass", "inertia", "origin", "mesh", "box", "cylinder", "sphere"):
        attributes = _NUMBERS.get(str(e.tag), ("scale", "size", "radius", "length"))
        for attribute in attributes:
            text = e.get(attribute)
            if text is None:
                continue
            try:
                values = [float(v) for v in text.split()]
            except ValueError:
                raise UrdfError(path, e.sourceline or 0, f"link '{name}': <{e.tag} {attribute}={text[:40]!r}> is "
                                                         "not numbers separated by spaces") from None
            if not all(math.isfinite(v) for v in values):
                raise UrdfError(path, e.sourceline or 0, f"link '{name}': <{e.tag} {attribute}={text[:40]!r}> "
                                                         "must be finite numbers (no nan or inf)")
            negative = e.tag == "mass" or (e.tag == "inertia" and attribute in ("ixx", "iyy", "izz"))
            if negative and any(v < 0 for v in values):
                raise UrdfError(path, e.sourceline or 0, f"link '{name}': <{e.tag} {attribute}={text!r}> is negative; "
                                                         "valid: >= 0")
            if e.tag in ("mesh", "box", "cylinder", "sphere") and any(v <= 0 for v in values):
                raise UrdfError(path, e.sourceline or 0, f"link '{name}': <{e.tag} {attribute}={text[:40]!r}> must "
                                                         "be > 0")


MESH_SEARCH_DEPTH = 4
"""How many parent directories of a URDF are searched for ``package://`` meshes."""


def resolve_mesh(filename: str, urdf_dir: Path) -> Path | None:
    """The file a URDF ``<mesh filename>`` names: relative to the URDF's directory, ``file://`` or
    ``package://<pkg>/...`` (searched in the URDF's directory and up to :data:`MESH_SEARCH_DEPTH` parents);
    ``None`` if there is no such file."""
    if filename.startswith("file://"):
        candidates = [Path(filename[len("file://"):])]
    elif filename.startswith("package://"):
        package, _, rel = filename[len("package://"):].partition("/")
        bases = [urdf_dir, *urdf_dir.parents][:MESH_SEARCH_DEPTH + 1]
        candidates = []
        for base in bases:
            if base.name == package:
                candidates.append(base / rel)
            candidates += [base / package / rel, base / rel]
    else:
        candidates = [Path(filename) if Path(filename).is_absolute() else urdf_dir / filename]
    return next((c.resolve() for c in candidates if c.is_file()), None)


def link_friction(root: etree._Element) -> dict[str, float]:
    """Sliding friction per link of a parsed URDF: ``<gazebo reference><mu1>`` (or ``<mu>``), else PyBullet's
    ``<link><contact><lateral_friction value>``; negative values count as 0, unreadable ones are ignored."""
    friction: dict[str, float] = {}
    for link in root.findall("link"):
        lateral = link.find("contact/lateral_friction")
        if lateral is not None:
            _put_friction(friction, link.get("name"), lateral.get("value"))
    for gazebo in root.findall("gazebo"):
        _put_friction(friction, gazebo.get("reference"), gazebo.findtext("mu1") or gazebo.findtext("mu"))
    return friction


def _put_friction(friction: dict[str, float], link: str | None, value: str | None) -> None:
    if link is None or value is None:
        return
    try:
        friction[str(link)] = max(0.0, float(value))
    except ValueError:
        return
