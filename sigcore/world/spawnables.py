"""The spawnables catalogue: the models a spawn request may name as ``model://NAME``.

Two sources, in this order (the first to offer a name keeps it; a later one is skipped with a warning naming both):

1. folders of a ``models/`` folder holding a ``spawnable.xml``: the one next to the world file
   (``<world file's folder>/models/``), then the repository's ``worlds/models/`` (found relative to the sigcore
   package; absent in an installed wheel). The folder's name is the spawnable's name;
2. plugins, through the hook ``sigcore_register_spawnables`` (:func:`sigcore.plugins.spawnables`).

A ``spawnable.xml`` holds exactly one world-format element, ``<robot>``, ``<object>`` or ``<human>``
(``docs/world-format.md``), with relative paths starting at its folder. Its ``description`` attribute is the
description listed by ``get_spawnables`` and, once spawned, the entity's own (``get_entity_info``); ``name`` is
optional (the spawned entity's default name), and ``pose`` is replaced by the spawn request's. A file that does
not read, is not one such element, or does not validate is left out with a warning naming the file and the
problem: a broken model never stops a run.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path

from lxml import etree

from .exceptions import SpawnableError, WorldError, WorldIssue
from .footprints import local_bounds
from .models import Entity, Spawnable, World, valid_name
from .parser import parse_world

log = logging.getLogger("sigcore.spawnables")

FILE = "spawnable.xml"
"""The file that makes a folder of ``models/`` a spawnable."""

REPOSITORY_MODELS = Path(__file__).resolve().parent.parent.parent / "worlds" / "models"
"""The repository's ``worlds/models`` (may not exist, e.g. when sigcore is installed from a wheel)."""

_KINDS = ("robot", "object", "human")
_DECLARATION = re.compile(r"\A\ufeff?\s*<\?xml[^>]*\?>")
_COMMENT = re.compile(r"<!--.*?-->", re.S)
_START = re.compile(r"<([A-Za-z_][\w.\-:]*)")


def find_spawnables(world: World, registered: Iterable[Spawnable] = ()) -> list[Spawnable]:
    """Every spawnable ``world`` may spawn: its ``models/`` folder's, the repository's, then ``registered``.

    Args:
        world: The running world (its file's folder may have a ``models/`` of its own).
        registered: The plugins' (``sigcore.plugins.spawnables()``, passed in by the caller: this layer does not
            know the registry); each is validated once, a broken one left out with a warning.

    Returns:
        The valid spawnables, by source then name; broken ones are left out with a warning.
    """
    found: dict[str, Spawnable] = {}

    def add(spawnable: Spawnable) -> None:
        first = found.get(spawnable.name)
        if first is not None:
            log.warning("spawnable '%s' of %s is ignored: %s offers it first", spawnable.name,
                        _where(spawnable), _where(first))
        else:
            found[spawnable.name] = spawnable

    for folder in _model_folders(world):
        for spawnable in folder_spawnables(folder):
            add(spawnable)
    for spawnable in sorted(registered, key=lambda s: s.name):
        if spawnable not in _PLUGINS:
            try:
                _PLUGINS[spawnable] = _validated(spawnable, Path(spawnable.base) / f"<plugin {spawnable.origin}>")
            except WorldError as e:
                log.warning("spawnable '%s' of plugin '%s' is left out: %s", spawnable.name, spawnable.origin, e)
                _PLUGINS[spawnable] = None
        checked = _PLUGINS[spawnable]
        if checked is not None:
            add(checked)
    return list(found.values())


def spawnable(world: World, name: str, registered: Iterable[Spawnable] = ()) -> Spawnable:
    """The spawnable called ``name`` (``model://NAME``) for ``world`` (``registered``: see :func:`find_spawnables`).

    Raises:
        KeyError: no such spawnable; the message lists the available ones.
    """
    every = find_spawnables(world, registered)
    for s in every:
        if s.name == name:
            return s
    raise KeyError(f"no spawnable '{name}'; available: {', '.join(s.name for s in every) or 'none'} "
                   f"(folders of worlds/models with a {FILE}, or a plugin's)")


def folder_spawnables(models: Path) -> list[Spawnable]:
    """The spawnables of one ``models/`` folder: each sub-folder with a ``spawnable.xml``, by name."""
    out = []
    origin = _origin(models)
    for file in sorted(models.glob(f"*/{FILE}")):
        name = file.parent.name
        if not valid_name(name):
            log.warning("%s is left out: the folder name '%s' is not a valid spawnable name (a letter, then "
                        "letters, digits or '_')", file, name)
            continue
        try:
            stat = file.stat()
        except OSError as e:
            log.warning("%s is left out: cannot read it (%s)", file, e)
            continue
        key = (file, stat.st_mtime_ns, stat.st_size, origin)
        if key not in _FILES:  # read, validated and warned about once per version of the file
            _FILES[key] = _folder_spawnable(file, name, origin)
        found = _FILES[key]
        if found is not None:
            out.append(found)
    return out


_FILES: dict[tuple[Path, int, int, str], Spawnable | None] = {}
"""Each ``spawnable.xml`` read so far, by (file, modification time [ns], size, origin): the spawnable, or None if
it is broken. A spawn names one, and validating a URDF model costs milliseconds. (A URDF edited while the
process runs is spawned as it is now; only the listed bounds may be those of the version first read.)"""
_PLUGINS: dict[Spawnable, Spawnable | None] = {}
"""Each plugin spawnable validated so far: the checked one, or None if it is broken."""


def _folder_spawnable(file: Path, name: str, origin: str) -> Spawnable | None:
    try:
        text = _read(file)
        return _validated(Spawnable(name, "", text, str(file.parent), origin), file)
    except (OSError, UnicodeDecodeError) as e:
        log.warning("%s is left out: cannot read it (%s)", file, e)
    except WorldError as e:
        log.warning("%s is left out: %s", file, e)
    return None


def parse_element(text: str, file: Path, name: str) -> tuple[Entity, World]:
    """Validate one world-format element as if it were in a world file ``file`` (relative paths start at its
    folder), called ``name`` when it has no ``name`` of its own.

    Args:
        text: One ``<robot>``, ``<object>`` or ``<human>`` element (an XML declaration and comments around it are
            allowed).
        file: Where it comes from (messages, relative paths).
        name: Its name if the element has none.

    Returns:
        The entity, and a one-entity world holding it (with its URDF, if any, read).

    Raises:
        SpawnableError: not one element of those kinds, or it does not validate; located in ``file``.
    """
    body = _DECLARATION.sub(lambda m: " " * len(m.group(0)), text, count=1)
    blank = _COMMENT.sub(lambda m: "".join(c if c == "\n" else " " for c in m.group(0)), body)
    tags = [(m.group(1), m.end()) for m in _START.finditer(blank)]
    if not tags or tags[0][0] not in _KINDS:
        got = f"<{tags[0][0]}>" if tags else "no element"
        raise SpawnableError([_issue(file, f"{got}; valid: one <robot>, <object> or <human> element of the world "
                                           "format")])
    end = _tag_end(blank, tags[0][1])
    if not re.search(r"(^|\s)name\s*=", blank[tags[0][1]:end]):  # named at the end: columns before stay true
        end -= blank[end - 1] == "/"
        body = f'{body[:end]} name="{name}"{body[end:]}'
    try:  # <world> on a line of its own: the element's lines are one further down
        world = parse_world(file, "<world>\n" + body + "\n</world>")
    except WorldError as e:
        raise SpawnableError([replace(i, line=max(1, i.line - 1)) for i in e.issues]) from None
    if len(world.agents) != 1 or len(world.entities) != 1:
        raise SpawnableError([_issue(file, f"{len(world.agents)} elements; valid: exactly one <robot>, <object> "
                                           "or <human>")])
    return world.entities[0], world


def _tag_end(text: str, pos: int) -> int:
    """Offset of the ``>`` that ends the start tag whose name ends at ``pos`` (quoted ``>`` skipped)."""
    quote = ""
    for i in range(pos, len(text)):
        c = text[i]
        if quote:
            quote = "" if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c == ">":
            return i
    return len(text)


def _validated(spawnable: Spawnable, file: Path) -> Spawnable:
    """``spawnable`` with its description and bounds read from its element; :class:`SpawnableError` if invalid."""
    entity, world = parse_element(spawnable.element, file, spawnable.name)
    try:
        bounds = local_bounds(entity, world)
    except (OSError, ValueError, KeyError) as e:  # an unreadable mesh: the bounds are unknown, not an error
        log.debug("bounds of spawnable '%s' unknown: %s", spawnable.name, e)
        bounds = None
    description = spawnable.description or entity.description
    return Spawnable(spawnable.name, description, _element_only(spawnable.element), spawnable.base,
                     spawnable.origin, bounds)


def _element_only(text: str) -> str:
    """The one element of a valid ``spawnable.xml`` text, without the XML declaration and comments around it."""
    body = _DECLARATION.sub("", text, count=1)
    root = etree.fromstring(f"<w>{body}</w>".encode(), parser=etree.XMLParser(resolve_entities=False))
    element = next(child for child in root if isinstance(child.tag, str))
    return etree.tostring(element, encoding="unicode", with_tail=False)


def _model_folders(world: World) -> list[Path]:
    """The world's own ``models/`` (if it comes from a file) and the repository's, each once."""
    out: list[Path] = []
    own = [world.base_dir / "models"] if world.source.is_file() else []  # a world from memory has no folder
    for folder in (*own, REPOSITORY_MODELS):
        if folder.is_dir() and folder.resolve() not in out:
            out.append(folder.resolve())
    return out


def _origin(models: Path) -> str:
    return "worlds/models" if models.resolve() == REPOSITORY_MODELS.resolve() else str(models)


def _where(spawnable: Spawnable) -> str:
    return f"plugin '{spawnable.origin}'" if not spawnable.base or not Path(spawnable.base, FILE).is_file() \
        else str(Path(spawnable.base, FILE))


def _read(file: Path) -> str:
    return file.read_bytes().decode("utf-8-sig")


def _issue(file: Path, message: str) -> WorldIssue:
    return WorldIssue(file, 1, 1, None, None, message)
