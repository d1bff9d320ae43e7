"""The worlds a running simulation may load (``load_world``): where they are found and how a request names one.

Sources, in order: the world the run started with, the repository's ``worlds/`` folder, the files and folders given
on the command line (``sigcore run WORLD --worlds PATH``, ``sim.worlds.sources``), and those plugins
register (``sigcore_register_worlds``). A folder contributes every ``*.xml`` directly in it whose root element is
``<world>``; only the root element is read (name, ``description``, ``tags``), so listing is fast and a world with
errors is still listed (loading it reports them).

A request names a world by a path, ``file://PATH``, ``package://PKG/PATH`` (as spawning does), or the name of a
listed world (``cleanup``), or gives the world's XML text.
"""

from __future__ import annotations

import io
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from ..text import clip
from .exceptions import SpawnRefusal, WorldError, WorldIssue, WorldRefusal, issue_code
from .resources import REPOSITORY, find_file, path_is

if TYPE_CHECKING:
    from .models import World

WORLDS_DIR = REPOSITORY / "worlds"
"""The worlds shipped with sigcore."""

TEXT_SOURCE = "<load_world resource_string>"
"""The file name a world given as text has in messages (its relative paths are resolved from the working
directory)."""


@dataclass(frozen=True)
class WorldResource:
    """One world that can be loaded.

    Attributes:
        name: The ``name`` of its ``<world>`` (not necessarily unique).
        path: The world file (absolute).
        description: Its ``description`` attribute.
        tags: Its ``tags``.
        source: Where it was found: ``current``, ``worlds/``, ``command line``, ``request`` or ``plugin NAME``.
    """

    name: str
    path: Path
    description: str = ""
    tags: tuple[str, ...] = ()
    source: str = ""

    @property
    def uri(self) -> str:
        """``file://`` URI of :attr:`path`."""
        return self.path.as_uri()


def read_header(path: Path, source: str) -> WorldResource | None:
    """The catalogue entry of world file ``path`` from its root element alone; None if it is no world file (not
    XML, or its root is not ``<world>``)."""
    try:
        for _, element in etree.iterparse(str(path), events=("start",), resolve_entities=False, no_network=True):
            if element.tag != "world":
                return None
            return WorldResource(str(element.get("name", "world")), path.resolve(),
                                 " ".join(str(element.get("description", "")).split()),
                                 tuple(str(element.get("tags", "")).split()), source)
    except (etree.XMLSyntaxError, OSError):
        return None
    return None


def _world_files(location: Path) -> list[Path]:
    if path_is(location, "is_dir"):
        return sorted(p for p in location.glob("*.xml") if path_is(p, "is_file"))
    return [location]


def find_worlds(sources: Iterable[tuple[Path, str]]) -> tuple[list[WorldResource], list[str]]:
    """The world files in ``sources`` (``(file or folder, source label)``), each file once (the first source that
    names it wins).

    Returns:
        The worlds, and a problem per source that does not exist or is no world file (one line each).
    """
    worlds: list[WorldResource] = []
    problems: list[str] = []
    seen: set[Path] = set()
    for location, label in sources:
        location = Path(location)
        if not path_is(location, "exists"):
            problems.append(f"{clip(str(location), 300)} ({label}): no such file or folder")
            continue
        for path in _world_files(location):
            resolved = path.resolve()
            if resolved in seen:
                continue
            entry = read_header(path, label)
            if entry is None:
                if not path_is(location, "is_dir"):
                    problems.append(f"{clip(str(location), 300)} ({label}): not a world file (its root element must "
                                    "be <world>)")
                continue
            seen.add(resolved)
            worlds.append(entry)
    return worlds, problems


def default_sources(current: Sequence[Path], extra: Sequence[Path] = (),
                    registered: Sequence[tuple[Path, str]] = ()) -> list[tuple[Path, str]]:
    """The catalogue's sources: the current world's file (and the one the run started with), ``worlds/``, ``extra``
    (the command line), and ``registered``: the plugins' ``(path, plugin name)`` (``sigcore.plugins.worlds()``,
    passed in by the caller: this layer does not know the registry)."""
    out: list[tuple[Path, str]] = [(path, "current") for path in current if path_is(path, "is_file")]
    out.append((WORLDS_DIR, "worlds/"))
    out += [(Path(p), "command line") for p in extra]
    out += [(path, f"plugin {name}") for path, name in registered]
    return out


def matches(world: WorldResource, tags: Sequence[str], match_all: bool) -> bool:
    """Whether ``world`` passes a tags filter (``match_all``: every tag; else any; no tags: every world)."""
    if not tags:
        return True
    have = set(world.tags)
    return all(t in have for t in tags) if match_all else any(t in have for t in tags)


def open_world(uri: str, text: str, catalogue: Sequence[WorldResource], base: World | None = None) -> World:
    """Parse the world a request names: ``uri`` (a path, ``file://``, ``package://``, or the name or file stem of a
    world of ``catalogue``), else ``text`` (the world's XML; relative paths from the working directory).

    Args:
        base: The world loaded now (``package://`` and relative paths also look beside it), if any.

    Raises:
        WorldRefusal: NO_RESOURCE (both empty), NOT_FOUND (no such file or listed world; names the valid ones),
            UNSUPPORTED_FORMAT (not a ``<world>`` of the sigcore format, e.g. SDF or MJCF), RESOURCE_PARSE_ERROR,
            MISSING_ASSETS, UNSUPPORTED_ASSETS, UNSUPPORTED_ELEMENTS (the world file's errors, located at
            ``file:line:column``).
    """
    from .parser import parse_world

    uri, has_text = uri.strip(), bool(text.strip())
    if not uri and not has_text:
        raise WorldRefusal("NO_RESOURCE", "neither uri nor resource_string is given; valid: a world file's path, "
                                          "file:// or package:// URI, the name of an available world, or a world's "
                                          "XML text")
    if uri:
        path = _locate(uri, catalogue, base)
        try:
            text = path.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as e:
            raise WorldRefusal("RESOURCE_PARSE_ERROR", f"cannot read {path}: {e}") from None
    else:
        path = Path.cwd() / TEXT_SOURCE
    root_tag = _root_tag(text)
    if root_tag is not None and root_tag != "world":
        raise WorldRefusal("UNSUPPORTED_FORMAT", f"{path.name}: the root element is <{root_tag}>; sigcore loads "
                                                 "its own world format (root <world>, docs/world-format.md), not "
                                                 "SDF, MJCF or USD")
    try:
        return parse_world(path, text)
    except WorldError as e:
        raise WorldRefusal(issue_code(e.issues), _summary(e.issues)) from None


def _summary(issues: Sequence[WorldIssue], most: int = 4) -> str:
    lines = [str(i) for i in issues[:most]]
    more = len(issues) - most
    return "; ".join(lines) + (f"; and {more} more" if more > 0 else "")


def _root_tag(text: str) -> str | None:
    """The root element's tag, or None when the text is not well-formed (the parser then says where)."""
    try:
        for _, element in etree.iterparse(io.BytesIO(text.encode("utf-8")), events=("start",), resolve_entities=False,
                                          no_network=True):
            return str(element.tag)
    except etree.XMLSyntaxError:
        return None
    return None


def _locate(uri: str, catalogue: Sequence[WorldResource], base: World | None) -> Path:
    if "://" not in uri:
        path = Path(uri).expanduser()
        if path_is(path, "is_file"):
            return path.resolve()
        for world in catalogue:
            if uri in (world.name, world.path.stem, world.path.name):
                return world.path
    if base is not None:
        try:
            return find_file(uri, base)
        except SpawnRefusal:
            pass
    elif uri.startswith("file://") and path_is(Path(uri[len("file://"):]), "is_file"):
        return Path(uri[len("file://"):]).resolve()
    elif uri.startswith("package://sigcore/") and path_is(REPOSITORY / uri[len("package://sigcore/"):], "is_file"):
        return (REPOSITORY / uri[len("package://sigcore/"):]).resolve()
    listed = ", ".join(f"{w.path.stem} ({w.path})" for w in catalogue[:12]) or "none"
    raise WorldRefusal("NOT_FOUND", f"no world file for {uri[:200]!r}; valid: a path, file:// or package:// URI, or "
                                    f"an available world: {listed}")
