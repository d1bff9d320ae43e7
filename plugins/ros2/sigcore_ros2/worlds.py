"""The simulation_interfaces world services: get_available_worlds, get_current_world, load_world, unload_world.

The core lists, parses, loads and unloads (``sigcore.world.catalogue``, ``sim.worlds.load`` /
``unload``); this module maps requests, sources and refusal codes. What the transport does when the world
changes (endpoints, /clock, state) follows the ``world`` event of ``sim.events`` (``Ros2Transport._world_changed``),
so a world loaded by a library user is served the same way.

Sources are local only: a path or a ``file://`` URI (``offline_only`` changes nothing). sigcore's world parser is
strict: ``fail_on_unsupported_element=false`` and ``ignore_missing_or_unsupported_assets=true`` cannot make it ignore
an element or an asset; such a world is refused with the same codes either way, and the message says so.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from simulation_interfaces.msg import Resource, Result, WorldResource
from simulation_interfaces.srv import GetAvailableWorlds, GetCurrentWorld, LoadWorld, UnloadWorld

from sigcore.text import clip, quote
from sigcore.world.catalogue import WorldResource as Listed
from sigcore.world.catalogue import find_worlds, matches, open_world
from sigcore.world.exceptions import WorldRefusal
from sigcore.world.resources import RefusalCode

from .exceptions import Refusal
from .siminfo import tags_of

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation
    from sigcore.world.models import World

LOAD_CODES: dict[RefusalCode, int] = {
    "UNSUPPORTED_FORMAT": LoadWorld.Response.UNSUPPORTED_FORMAT, "NO_RESOURCE": LoadWorld.Response.NO_RESOURCE,
    "RESOURCE_PARSE_ERROR": LoadWorld.Response.RESOURCE_PARSE_ERROR,
    "MISSING_ASSETS": LoadWorld.Response.MISSING_ASSETS, "UNSUPPORTED_ASSETS": LoadWorld.Response.UNSUPPORTED_ASSETS,
    "UNSUPPORTED_ELEMENTS": LoadWorld.Response.UNSUPPORTED_ELEMENTS, "NOT_FOUND": Result.RESULT_NOT_FOUND,
    "OPERATION_FAILED": Result.RESULT_OPERATION_FAILED,
}
"""The core's world refusal codes (:class:`sigcore.world.exceptions.WorldRefusal`) as LoadWorld result codes."""

SERVICES = {"get_available_worlds": GetAvailableWorlds, "get_current_world": GetCurrentWorld,
            "load_world": LoadWorld, "unload_world": UnloadWorld}
"""The world services, by name (under the transport's ``sim_prefix``)."""

NO_WORLD = "no world is loaded; load one first (load_world)"


def _ok(message: str = "") -> Result:
    return Result(result=Result.RESULT_OK, error_message=message)


def local_source(source: str) -> str:
    """The path of an ``additional_sources`` entry: a path as it is, a ``file://`` URI without its scheme.

    Raises:
        ValueError: any other URI (``http://``, ``package://``...): only local paths are searched.
    """
    path = source[len("file://"):] if source.startswith("file://") else source
    if "://" in path:
        raise ValueError(f"{quote(source)}: only local paths and file:// URIs are searched")
    return path


class WorldServices:
    """The four world services (run on the simulation thread through the receiver, like
    :class:`~sigcore_ros2.siminterfaces.SimInterfaces`' own, which dispatches to them).

    Args:
        sim: The simulation.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self._text: tuple[World, str] | None = None  # the world load_world got as resource_string, and that text

    def resource(self, world: World) -> WorldResource:
        """``world`` as a WorldResource: its file's URI, or (given as text to load_world) its text."""
        if world.source.is_file():
            resource = Resource(uri=world.source.resolve().as_uri())
        else:
            text = self._text[1] if self._text is not None and self._text[0] is world else ""
            resource = Resource(resource_string=text)
        return WorldResource(name=world.name, world_resource=resource, description=world.description,
                             tags=list(world.tags))

    # ------------------------------------------------------------------ services: (request, response, reply)
    # Each fills ``response`` and returns False (answered at once), like SimInterfaces' own.
    def get_available_worlds(self, req: Any, res: Any, reply: Any) -> bool:
        """The loadable worlds (``sim.worlds.available``) passing ``req.filter``; ``additional_sources`` are
        local files or folders (paths or ``file://`` URIs). A default source that failed (a ``--worlds`` path or a
        plugin's that is gone) is DEFAULT_SOURCES_FAILED, an additional one OPERATION_FAILED, unless
        ``continue_on_error`` (then OK with the problems in ``error_message``, if any world was found).
        ``offline_only`` changes nothing: every source is local.

        Raises:
            Refusal: an unknown tags filter mode.
        """
        tags, match_all = tags_of(req.filter)
        paths: list[str] = []
        refused: list[str] = []
        for source in req.additional_sources:
            try:
                paths.append(local_source(str(source)))
            except ValueError as e:
                refused.append(str(e))
        worlds, problems = self.sim.worlds.available(paths)
        extra = set(find_worlds([(Path(p), "request") for p in paths])[1])
        extra_problems = refused + [p for p in problems if p in extra]
        default_problems = [p for p in problems if p not in extra]
        every = default_problems + extra_problems
        res.worlds = [self._listed(w) for w in worlds if matches(w, sorted(tags), match_all)]
        if every and not (req.continue_on_error and worlds):
            code = (GetAvailableWorlds.Response.DEFAULT_SOURCES_FAILED if default_problems
                    else Result.RESULT_OPERATION_FAILED)
            res.worlds = []
            res.result = Result(result=code, error_message=clip("; ".join(every), 2000)
                                + " (continue_on_error=true lists the worlds of the other sources)")
            return False
        res.result = _ok(clip("sources that failed: " + "; ".join(every), 2000) if every else "")
        return False

    @staticmethod
    def _listed(world: Listed) -> WorldResource:
        return WorldResource(name=world.name, world_resource=Resource(uri=world.uri), description=world.description,
                             tags=list(world.tags))

    def get_current_world(self, req: Any, res: Any, reply: Any) -> bool:
        """The loaded world (NO_WORLD_LOADED when none)."""
        if not self.sim.worlds.loaded:
            res.result = Result(result=GetCurrentWorld.Response.NO_WORLD_LOADED, error_message=NO_WORLD)
            return False
        res.world = self.resource(self.sim.world)
        res.result = _ok()
        return False

    def load_world(self, req: Any, res: Any, reply: Any) -> bool:
        """Replace the running world (``uri``: a path, ``file://`` or ``package://`` URI, or an available world's
        name; else ``resource_string``, the world's XML); the new one is STOPPED at time 0. A refused request leaves
        the running world as it was (the core parses and checks before unloading).

        Raises:
            Refusal: the simulation is quitting (OPERATION_FAILED), or the core's refusal with its code.
        """
        if self.sim.control.stopping:
            raise Refusal(Result.RESULT_OPERATION_FAILED, "load_world refused: the simulation is quitting")
        uri, text = str(req.uri), str(req.resource_string)
        sim = self.sim
        try:
            world = open_world(uri, text, sim.worlds.available()[0], base=sim.world if sim.worlds.loaded else None)
        except WorldRefusal as refusal:
            raise _load_refusal(refusal, req) from None
        try:
            sim.inputs.load_world(world, uri, text)
        except WorldRefusal as refusal:
            raise _load_refusal(refusal, req) from None
        self._text = (world, text) if not uri.strip() else None
        res.world = self.resource(world)
        res.result = _ok()
        return False

    def unload_world(self, req: Any, res: Any, reply: Any) -> bool:
        """Remove the running world (NO_WORLD_LOADED when none): the state is NO_WORLD until load_world.

        Raises:
            Refusal: the simulation is quitting (OPERATION_FAILED).
        """
        if self.sim.control.stopping:
            raise Refusal(Result.RESULT_OPERATION_FAILED, "unload_world refused: the simulation is quitting")
        if not self.sim.worlds.loaded:
            res.result = Result(result=UnloadWorld.Response.NO_WORLD_LOADED, error_message=NO_WORLD)
            return False
        self.sim.inputs.unload_world()
        self._text = None
        res.result = _ok()
        return False


def _load_refusal(refusal: WorldRefusal, req: Any) -> Refusal:
    """The LoadWorld answer to the core's ``refusal``; the message says so when the request asked to ignore what
    sigcore never ignores."""
    code, note = refusal.code, ""
    if code == "UNSUPPORTED_ELEMENTS" and not req.fail_on_unsupported_element:
        note = " (sigcore never ignores elements: fail_on_unsupported_element=false changes nothing)"
    elif code in ("MISSING_ASSETS", "UNSUPPORTED_ASSETS") and req.ignore_missing_or_unsupported_assets:
        note = " (sigcore never ignores assets: ignore_missing_or_unsupported_assets=true changes nothing)"
    return Refusal(LOAD_CODES.get(code, Result.RESULT_OPERATION_FAILED), str(refusal) + note)
