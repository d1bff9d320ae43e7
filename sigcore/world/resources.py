"""Spawn requests and their resolution into validated world models: what a request may name, the refusals.

A spawn request names what to add the way simulation_interfaces does (``uri`` or ``resource``, a name, a pose,
a namespace); :func:`resource_element` and :func:`build_model` turn it into a validated world model (a ``Robot``,
``Object`` or ``Human``); :meth:`sigcore.sim.Simulation.spawn` adds it to the running world (one backend call for
many) and tells every owner of per-entity state (``sigcore.sim.spawn.EntityChange``). This layer knows the world
format only: it imports nothing of the simulation, the recordings or the plugin registry.

What a request may name (``uri``, else ``resource``):

* a spawnable: ``model://NAME`` (a folder of ``worlds/models/`` or a plugin's, see :mod:`sigcore.world.spawnables`);
* a URDF file: a path, ``file://PATH`` or ``package://PKG/PATH`` ending in ``.urdf``; a URDF with movable joints
  becomes a robot (joint servos, no drive), one without becomes an object;
* a mesh file (``.obj``, ``.stl``): an object of that shape;
* a sigcore element file (``.xml``) holding one ``<robot>``, ``<object>`` or ``<human>`` of the world format;
* ``resource``: the text of a URDF (``<robot name=...><link .../>...``) or of one world-format element
  (``<object shape="box" size="0.1 0.1 0.1" tags="trash"/>``; relative paths in it start at the world file's
  folder).
"""

from __future__ import annotations

import copy
import os
import re
import uuid
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from lxml import etree

from ..geometry import quat_to_rpy
from .exceptions import RefusalCode, SpawnRefusal, UrdfError, WorldError, issue_code
from .models import Entity, Spawnable, World, valid_name
from .parser import parse_world
from .urdf import UrdfDocument, read_urdf


@dataclass(frozen=True)
class SpawnRequest:
    """One entity to add while running.

    Attributes:
        name: Its name (a letter, then letters, digits, ``_``); empty: the resource's own name (a URDF's
            ``<robot name>``, an element's ``name``), renamed if ``allow_renaming``.
        uri: What to spawn (see the module docstring); empty: ``resource`` is used.
        resource: The text of a URDF or of one world-format element, when ``uri`` is empty.
        xyz: Position [m] in ``frame``.
        wxyz: Orientation (w, x, y, z) in ``frame`` (normalised; a zero or non-finite quaternion is refused).
        frame: ``world`` or ``""`` (the same), or an entity's name: the pose is relative to that entity's main part.
        namespace: ROS namespace of the entity's endpoints (``/ns``); empty: none.
        allow_renaming: When the name is taken or empty, pick a free one (``name_1``, ``name_2``...).
        tags: Tags added to the resource's own.
    """

    name: str = ""
    uri: str = ""
    resource: str = ""
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    frame: str = ""
    namespace: str = ""
    allow_renaming: bool = False
    tags: tuple[str, ...] = ()


# ------------------------------------------------------------------------------------------------ resolution
MESH_SUFFIXES = (".obj", ".stl")
"""Mesh files a request may name (an object of that shape)."""

SPAWN_FORMATS = ("urdf", "sigcore", "obj", "stl")
"""What ``uri`` or ``resource`` may hold (announced as simulation_interfaces ``spawn_formats``)."""

_NAMESPACE = re.compile(r"^/?([A-Za-z][A-Za-z0-9_]*)(/[A-Za-z][A-Za-z0-9_]*)*$")
_AGENT_TAGS = ("robot", "object", "human")


def normalize_namespace(namespace: str) -> str:
    """``""`` or ``/a/b`` from ``a/b``, ``/a/b`` or ``/a/b/``.

    Raises:
        SpawnRefusal: NAMESPACE_INVALID, naming the rule.
    """
    ns = namespace.strip().rstrip("/")
    if not ns:
        return ""
    if _NAMESPACE.fullmatch(ns) is None:
        raise SpawnRefusal("NAMESPACE_INVALID", f"namespace {ns[:80]!r} is not a ROS namespace; valid: names of a "
                                                "letter then letters, digits or '_', separated by '/', e.g. '/team_a'")
    return ns if ns.startswith("/") else "/" + ns


def check_pose(xyz: Sequence[float], wxyz: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The position and the normalised quaternion of a request.

    Raises:
        SpawnRefusal: INVALID_POSE: a non-finite number, or a quaternion of length 0.
    """
    pos = np.asarray(xyz, dtype=float)
    quat = np.asarray(wxyz, dtype=float)
    if pos.shape != (3,) or quat.shape != (4,) or not (np.all(np.isfinite(pos)) and np.all(np.isfinite(quat))):
        raise SpawnRefusal("INVALID_POSE", f"pose position {tuple(float(v) for v in pos.ravel())} / orientation "
                                           f"{tuple(float(v) for v in quat.ravel())} holds a non-finite number; "
                                           "valid: finite numbers, a quaternion (w, x, y, z) of length > 0")
    if float(np.abs(pos).max()) > MAX_COORDINATE:
        raise SpawnRefusal("INVALID_POSE", f"position {tuple(round(float(v), 3) for v in pos)} is beyond "
                                           f"{MAX_COORDINATE:g} m from the origin; valid: |x|, |y|, |z| <= "
                                           f"{MAX_COORDINATE:g} [m]")
    norm = float(np.linalg.norm(quat))
    if norm < 1e-9:
        raise SpawnRefusal("INVALID_POSE", "orientation quaternion has length 0; valid: (w, x, y, z) of length > 0, "
                                           "e.g. (1, 0, 0, 0)")
    return pos, quat / norm


MAX_COORDINATE = 1e4
"""Farthest a spawn pose may be from the origin on any axis [m]."""


def find_file(uri: str, world: World) -> Path:
    """The file a ``uri`` names: a path (relative to the world file's folder), ``file://PATH``, or
    ``package://PKG/PATH`` (``PKG`` searched in ``$AMENT_PREFIX_PATH/share``, the world file's folder and its
    ``models/``, the repository's ``worlds/models``; ``package://sigcore/...`` is the repository).

    Raises:
        SpawnRefusal: NOT_FOUND, naming the places searched.
    """
    if uri.startswith("file://"):
        candidates = [Path(uri[len("file://"):])]
    elif uri.startswith("package://"):
        package, _, rel = uri[len("package://"):].partition("/")
        bases = [Path(p) / "share" / package for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
        bases += [world.base_dir / package, world.base_dir / "models" / package, MODELS_DIR / package]
        if package == "sigcore":
            bases.append(REPOSITORY)
        candidates = [b / rel for b in bases]
    else:
        path = Path(uri)
        candidates = [path if path.is_absolute() else world.base_dir / path]
    for candidate in candidates:
        if path_is(candidate, "is_file"):
            return candidate.resolve()
    raise SpawnRefusal("NOT_FOUND", f"no file for uri {uri[:200]!r}; looked at "
                                    f"{', '.join(str(c) for c in candidates[:6])}")


def path_is(path: Path, kind: str) -> bool:
    """``path.is_file()`` / ``is_dir()`` / ``exists()`` (``kind``), False where the OS refuses the name (e.g. too
    long) instead of raising."""
    try:
        return bool(getattr(path, kind)())
    except (OSError, ValueError):
        return False


REPOSITORY = Path(__file__).resolve().parents[2]
"""The sigcore repository (``package://sigcore/...``)."""

MODELS_DIR = REPOSITORY / "worlds" / "models"
"""The models shipped with sigcore (the spawnables of ``model://NAME``)."""


def _element_of_urdf(path: Path, name: str) -> etree._Element:
    """A world-format element for a URDF file: ``<robot>`` if it has movable joints, else ``<object>``."""
    try:
        model = read_urdf(path)
    except UrdfError as e:
        raise SpawnRefusal("RESOURCE_PARSE_ERROR", f"invalid URDF: {e}") from None
    element = etree.Element("robot" if model.movable_joints else "object")
    element.set("urdf", str(path))
    if name:
        element.set("name", name)
    return element


def resource_element(request: SpawnRequest, world: World, spawn_dir: Path,
                     spawnable: Callable[[str], Spawnable]) -> tuple[etree._Element, Path, str]:
    """The world-format element a request names, the folder its relative paths start from, and a default name.

    Raises:
        SpawnRefusal: NO_RESOURCE, NOT_FOUND (a file or spawnable), UNSUPPORTED_FORMAT, RESOURCE_PARSE_ERROR.
    """
    uri = request.uri.strip()
    if uri.startswith("model://"):
        name = uri[len("model://"):].strip("/")
        try:
            found = spawnable(name)
        except KeyError as e:
            raise SpawnRefusal("NOT_FOUND", str(e).strip("\"'")) from None
        return _parse_element(found.element, f"spawnable {uri}"), Path(found.base), found.name
    if uri:
        path = find_file(uri, world)
        suffix = path.suffix.lower()
        if suffix == ".urdf":
            return _element_of_urdf(path, ""), path.parent, _urdf_name(path)
        if suffix in MESH_SUFFIXES:
            element = etree.Element("object")
            element.set("mesh", str(path))
            return element, path.parent, path.stem
        if suffix == ".xml":
            try:
                text = path.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as e:
                raise SpawnRefusal("RESOURCE_PARSE_ERROR", f"cannot read {path}: {e}") from None
            return _parse_element(text, str(path)), path.parent, path.stem
        raise SpawnRefusal("UNSUPPORTED_FORMAT", f"{path.name}: files of type '{suffix or 'none'}' cannot be "
                                                 f"spawned; valid: .urdf, .obj, .stl, .xml (one world-format element) "
                                                 "or model://NAME")
    text = request.resource.strip()
    if not text:
        raise SpawnRefusal("NO_RESOURCE", "both uri and resource are empty; valid: a uri (model://NAME, a .urdf, "
                                          ".obj, .stl or .xml file) or the text of a URDF or of one world element")
    element = _parse_element(text, "resource")
    if element.tag == "robot" and element.find("link") is not None:  # a URDF's text
        spawn_dir.mkdir(parents=True, exist_ok=True)
        name = str(element.get("name", "")).strip()
        path = spawn_dir / f"{uuid.uuid4().hex}.urdf"
        path.write_text(text, encoding="utf-8")
        try:
            return _element_of_urdf(path, ""), world.base_dir, name
        except SpawnRefusal as refusal:  # name the request's text, not the file it was written to
            raise SpawnRefusal(refusal.code, str(refusal).replace(str(path), "resource")) from None
    return element, world.base_dir, ""


def _urdf_name(path: Path) -> str:
    try:
        return str(UrdfDocument.read(path).root.get("name", "")).strip() or path.stem
    except UrdfError:
        return path.stem


def _parse_element(text: str, what: str) -> etree._Element:
    try:
        element = etree.fromstring(text.encode("utf-8"), parser=etree.XMLParser(resolve_entities=False))
    except etree.XMLSyntaxError as e:
        raise SpawnRefusal("RESOURCE_PARSE_ERROR", f"{what}: not well-formed XML: {e.msg}") from None
    if element.tag == "robot" and element.find("link") is not None:
        return element
    if element.tag not in _AGENT_TAGS:
        raise SpawnRefusal("UNSUPPORTED_FORMAT", f"{what}: <{element.tag}> cannot be spawned; valid: a URDF "
                                                 "(<robot name=...> with <link>s) or one world-format <robot>, "
                                                 "<object> or <human> element")
    return element


def unique_name(wanted: str, taken: Collection[str], allow_renaming: bool) -> str:
    """The name to give: ``wanted`` if valid and free, else (``allow_renaming``) the first free ``wanted_N``
    (an invalid ``wanted`` is cleaned first: other characters become ``_``, a leading digit gets ``e``).

    Raises:
        SpawnRefusal: NAME_INVALID or NAME_NOT_UNIQUE when renaming is not allowed.
    """
    if not allow_renaming:
        if not wanted:
            raise SpawnRefusal("NAME_INVALID", "no name given and renaming not allowed; valid: a name (a letter, "
                                               "then letters, digits or '_'), or allow_renaming")
        if not valid_name(wanted) or len(wanted) > MAX_NAME:
            raise SpawnRefusal("NAME_INVALID", f"name {wanted[:80]!r} is not valid; valid: a letter, then letters, "
                                               f"digits or '_', at most {MAX_NAME} characters")
        if wanted in taken:
            raise SpawnRefusal("NAME_NOT_UNIQUE", f"name '{wanted}' is taken ({taken_what(wanted, taken)}); "
                                                  "choose another or set allow_renaming")
        return wanted
    base = re.sub(r"[^A-Za-z0-9_]", "_", wanted)[:MAX_NAME - 6] or "entity"
    if not base[0].isalpha():
        base = "e" + base
    if base not in taken:
        return base
    n = 1
    while f"{base}_{n}" in taken:
        n += 1
    return f"{base}_{n}"


def taken_what(name: str, taken: Collection[str]) -> str:
    """What holds ``name`` when ``taken`` says (a dict of name -> what), else 'an agent'."""
    return str(taken[name]) if isinstance(taken, Mapping) else "an agent has it"  # type: ignore[index]


MAX_NAME = 64
"""Longest entity name (the world format's rule)."""


def build_model(world: World, element: etree._Element, base: Path, name: str, pose: tuple[np.ndarray, np.ndarray],
                tags: Sequence[str]) -> Entity:
    """Validate ``element`` (renamed ``name``, at ``pose``, ``tags`` added, relative paths made absolute from
    ``base``) with the world parser, as if it stood in a world file.

    Raises:
        SpawnRefusal: RESOURCE_PARSE_ERROR (an attribute or child is wrong; URDF problems), MISSING_ASSETS (a
            file it names does not exist), UNSUPPORTED_ASSETS (a mesh in a format sigcore cannot read).
    """
    element = copy.deepcopy(element)
    element.set("name", name)
    xyz, wxyz = pose
    rpy = quat_to_rpy(wxyz)
    element.set("pose", " ".join(f"{float(v)!r}" for v in (*xyz, *rpy)))
    if tags:
        own = str(element.get("tags", "")).split()
        element.set("tags", " ".join([*own, *(t for t in tags if t not in own)]))
    for attr in ("urdf", "mesh"):
        raw = element.get(attr)
        if raw is not None and raw.strip() and not Path(raw.strip()).is_absolute():
            element.set(attr, str((base / raw.strip()).resolve()))
    text = f'<world timestep="{world.timestep!r}">{etree.tostring(element, encoding="unicode")}</world>'
    try:
        parsed = parse_world(base / "<spawn request>", text)
    except WorldError as e:
        detail = "; ".join(f"<{i.element}>{' ' + repr(i.attribute) if i.attribute else ''}: {i.message}"
                           for i in e.issues[:4])
        code: RefusalCode = issue_code(e.issues)
        if code == "UNSUPPORTED_ELEMENTS":  # SpawnEntity has no such code
            code = "RESOURCE_PARSE_ERROR"
        raise SpawnRefusal(code, f"entity '{name}': {detail}") from None
    entity = parsed.entities[0]
    return entity
