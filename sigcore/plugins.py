"""Plugin discovery and the registries of backends, transports, features, controllers, spawnables and worlds.

A plugin is a module (or any object) with ``@sigcore.hookimpl`` functions named after
:mod:`sigcore.hookspecs`. Installed plugins are found through entry points of group ``sigcore`` by
:func:`load_plugins`; nothing loads at import time, and every lookup (:func:`backends`, :func:`get_backend`,
...) loads first. Each plugin's registration hooks are called once, on their own, when the plugin is added: so
a plugin that fails to import or whose hook raises (``sys.exit`` included) is disabled and reported by name
(:func:`plugin_infos`) while the others load, and what each plugin provides is known. When two plugins register
the same name, the first one loaded keeps it and a warning names both.
"""

from __future__ import annotations

import difflib
import importlib.metadata
import inspect
import logging
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pluggy

from . import hookspecs
from .errors import PluginError, PluginLoadError
from .isolation import USER_ERRORS, describe

if TYPE_CHECKING:
    from .backend import Backend
    from .feature import Feature
    from .transport import Transport
    from .viewer import Viewer
    from .world.models import Spawnable

GROUP = "sigcore"
"""Entry-point group that plugin distributions declare."""
DISABLE_ENV = "SIGCORE_DISABLE_PLUGIN_AUTOLOAD"
"""If set (non-empty), entry points are not loaded; plugins can still be added by :func:`register_plugin`."""
KINDS = ("backend", "transport", "feature", "controller", "spawnable", "world", "viewer")
"""What a plugin can register, in the order :attr:`PluginInfo.provides` lists them."""
_HOOKS = {kind: f"sigcore_register_{kind}s" for kind in KINDS}
_SPECS = sorted(name for name in vars(hookspecs) if name.startswith("sigcore_"))

log = logging.getLogger("sigcore.plugins")
hookimpl = pluggy.HookimplMarker("sigcore")
pm = pluggy.PluginManager("sigcore")
pm.add_hookspecs(hookspecs)


@dataclass(frozen=True)
class PluginInfo:
    """One plugin: where it comes from, whether it loaded, and what it provides.

    Attributes:
        name: Entry-point name (or the name given to :func:`register_plugin`).
        distribution: Distribution declaring the entry point (``sigcore-backend-mujoco``); ``""`` in-process.
        version: That distribution's version; ``""`` in-process.
        error: Why the plugin is disabled (where it failed, ``Type: message``), or ``None`` if it loaded.
        module: The entry point's target (``package`` or ``package.module:attr``) or the object's module.
        provides: Names in effect by kind (``backend``, ``transport``, ``feature``, ``controller``,
            ``spawnable``, ``world``: a world file's or folder's path, ``viewer``); a name that another plugin
            registered first is left out (a warning names both).
    """

    name: str
    distribution: str
    version: str
    error: str | None = None
    module: str = ""
    provides: Mapping[str, tuple[str, ...]] = field(default_factory=dict, hash=False)

    @property
    def loaded(self) -> bool:
        """Whether the plugin loaded (``error`` is ``None``)."""
        return self.error is None

    def provided(self) -> list[str]:
        """What it provides as ``"kind name"`` strings, e.g. ``["backend mujoco"]``."""
        return [f"{kind} {name}" for kind in KINDS for name in self.provides.get(kind, ())]

    def describe(self) -> str:
        """``'mujoco' (sigcore-backend-mujoco 0.1.0)``, or ``'name' (in-process)``."""
        origin = f"{self.distribution} {self.version}".strip() or "in-process"
        return f"'{self.name}' ({origin})"


@dataclass
class _Record:
    name: str
    distribution: str
    version: str
    module: str
    plugin: object | None = None
    error: str | None = None
    found: dict[str, list[tuple[str, Any]]] = field(default_factory=dict)

    def info(self, provides: Mapping[str, tuple[str, ...]] | None = None) -> PluginInfo:
        return PluginInfo(self.name, self.distribution, self.version, self.error, self.module, provides or {})


@dataclass
class _State:
    loaded: bool = False
    records: list[_Record] = field(default_factory=list)
    registry: dict[str, dict[str, Any]] | None = None
    infos: list[PluginInfo] = field(default_factory=list)


_state = _State()


# ------------------------------------------------------------------ loading
def load_plugins() -> list[PluginInfo]:
    """Load the installed plugins once and return :func:`plugin_infos`. Idempotent.

    Entry points of group ``sigcore`` are loaded in the order of (entry-point name, distribution), unless
    ``SIGCORE_DISABLE_PLUGIN_AUTOLOAD`` is set. A plugin that fails to import, implements a hook that does not
    exist, or whose registration hook raises is disabled, logged and recorded with its error; the others still
    load.
    """
    if not _state.loaded:
        _state.loaded = True
        if not os.environ.get(DISABLE_ENV):
            found = importlib.metadata.entry_points(group=GROUP)
            for ep in sorted(found, key=lambda ep: (ep.name, _dist(ep))):
                _load_entry_point(ep)
    _sync()
    return list(_state.infos)


def plugin_infos() -> list[PluginInfo]:
    """Every plugin, loaded or failed, in load order (loads them first)."""
    return load_plugins()


def register_plugin(plugin: object, name: str | None = None) -> PluginInfo:
    """Add a plugin from inside the process (a test, a notebook, autoload disabled) as if it were installed.

    Raises:
        PluginLoadError: the name is taken, a hook name is unknown, or a registration hook raised.
    """
    load_plugins()
    name = name or pm.get_canonical_name(plugin)
    rec = _Record(name, "", "", getattr(plugin, "__name__", type(plugin).__module__))
    if any(r.name == name for r in _state.records) or pm.has_plugin(name):
        rec.error = f"a plugin named '{name}' is already registered"
        raise PluginLoadError(rec.info())
    _add(rec, plugin, keep_failed=False)
    if rec.error is not None:
        raise PluginLoadError(rec.info())
    _sync()
    return next(info for info in _state.infos if info.name == name)


def reset_for_tests() -> None:
    """Unregister every plugin and forget what was loaded; the next lookup discovers entry points again."""
    for name, plugin in list(pm.list_name_plugin()):
        if plugin is not None:
            pm.unregister(name=name)
    global _state
    _state = _State()


def _dist(ep: importlib.metadata.EntryPoint) -> tuple[str, str]:
    dist = ep.dist
    return (dist.name, dist.version) if dist is not None else ("", "")


def _load_entry_point(ep: importlib.metadata.EntryPoint) -> None:
    rec = _Record(ep.name, *_dist(ep), ep.value)
    taken = next((r for r in _state.records if r.name == ep.name), None)
    if taken is not None:
        rec.error = f"entry-point name '{ep.name}' is already used by {taken.info().describe()}; rename one"
        _state.records.append(rec)
        log.warning("sigcore plugin %s is disabled: %s", rec.info().describe(), rec.error)
        return
    try:
        plugin = ep.load()
    except USER_ERRORS as e:  # a broken third-party plugin (even one calling sys.exit) must not stop the others
        rec.error = f"importing '{ep.value}' raised {describe(e)}"
        _state.records.append(rec)
        log.warning("sigcore plugin %s failed to load and is disabled: %s", rec.info().describe(), rec.error)
        return
    _add(rec, plugin, keep_failed=True)


def _add(rec: _Record, plugin: object, keep_failed: bool) -> None:
    """Register ``plugin`` with pluggy, check its hooks, call its registration hooks; disable it on error."""
    try:
        pm.register(plugin, name=rec.name)
    except Exception as e:  # pluggy's PluginValidationError (bad hook signature) or a duplicate object
        rec.error = f"{type(e).__name__}: {e}"
    else:
        rec.error = _check_hooks(plugin) or _scan(rec, plugin)
        if rec.error is None:
            rec.plugin = plugin
        else:
            pm.unregister(plugin)
    if rec.error is None or keep_failed:
        _state.records.append(rec)
        _state.registry = None
    if rec.error is not None and keep_failed:
        log.warning("sigcore plugin %s failed to load and is disabled: %s", rec.info().describe(), rec.error)


def _check_hooks(plugin: object) -> str | None:
    """What ``pm.check_pending()`` checks, for this plugin only: every hook it implements has a spec."""
    callers = pm.get_hookcallers(plugin) or []
    for caller in callers:
        if caller.has_spec():
            continue
        if all(impl.optionalhook for impl in caller.get_hookimpls() if impl.plugin is plugin):
            continue
        close = difflib.get_close_matches(caller.name, _SPECS, n=1)
        hint = f"did you mean '{close[0]}'?" if close else f"hooks: {', '.join(_SPECS)}"
        return f"unknown hook '{caller.name}' ({hint})"
    implemented = {caller.name for caller in callers}
    for name in _SPECS:
        if name not in implemented and name in dir(plugin):
            log.warning("sigcore plugin '%s' defines %s without @sigcore.hookimpl; it is ignored",
                        pm.get_name(plugin), name)
    return None


def _scan(rec: _Record, plugin: object) -> str | None:
    """Call the plugin's own registration hooks (not the others'); the error, or None."""
    rec.found = {}
    for kind, hook_name in _HOOKS.items():
        found: list[tuple[str, Any]] = []
        kwargs = {"register": _registrar(kind, found, rec.name)}
        for impl in getattr(pm.hook, hook_name).get_hookimpls():
            if impl.plugin is not plugin:
                continue
            if impl.hookwrapper or impl.wrapper:
                return f"{hook_name} must not be a hook wrapper"
            try:
                impl.function(*(kwargs[arg] for arg in impl.argnames))
            except USER_ERRORS as e:
                return f"{hook_name} raised {describe(e)}"
        rec.found[kind] = found
    return None


def _registrar(kind: str, found: list[tuple[str, Any]], plugin: str) -> Callable[..., None]:
    """The ``register`` callback handed to plugin ``plugin``'s hook: it validates what it gets."""
    from .agent.controller import Controller
    from .backend import Backend
    from .feature import Feature
    from .transport import Transport
    from .viewer import Viewer

    bases: dict[str, type] = {"backend": Backend, "transport": Transport, "feature": Feature,
                              "controller": Controller, "viewer": Viewer}
    if kind == "spawnable":
        return _spawnable_registrar(found, plugin)
    if kind == "world":
        return _world_registrar(found, plugin)
    base = bases[kind]

    def check(name: object, cls: object) -> None:
        if not (isinstance(cls, type) and issubclass(cls, base)):
            raise TypeError(f"{kind} {cls!r} is not a subclass of {base.__module__}.{base.__qualname__}")
        if inspect.isabstract(cls):
            missing = ", ".join(sorted(getattr(cls, "__abstractmethods__", ())))
            raise TypeError(f"{kind} {cls.__qualname__} does not implement {missing}")
        if not isinstance(name, str) or not name:
            raise ValueError(f"{kind} {cls.__qualname__} needs a non-empty name, got {name!r}")
        found.append((name, cls))

    if kind == "controller":
        def register_controller(name: str, cls: type[Controller]) -> None:
            check(name, cls)
        return register_controller

    def register(cls: type) -> None:
        check(getattr(cls, "name", None), cls)
    return register


def _spawnable_registrar(found: list[tuple[str, Any]], plugin: str) -> Callable[[Spawnable], None]:
    """``register(Spawnable)``: a valid name, not registered twice by this plugin; its origin becomes ``plugin``."""
    from dataclasses import replace

    from .world.models import Spawnable, valid_name

    def register(spawnable: Spawnable) -> None:
        if not isinstance(spawnable, Spawnable):
            raise TypeError(f"spawnable {spawnable!r} is not a sigcore.world.models.Spawnable")
        if not valid_name(spawnable.name):
            raise ValueError(f"spawnable name {spawnable.name!r} is invalid; valid: a letter, then letters, "
                             "digits or '_'")
        if any(name == spawnable.name for name, _ in found):
            raise ValueError(f"spawnable '{spawnable.name}' is registered twice by plugin '{plugin}'")
        found.append((spawnable.name, replace(spawnable, origin=plugin)))
    return register


def _world_registrar(found: list[tuple[str, Any]], plugin: str) -> Callable[[Any], None]:
    """``register(path)``: a world file or a folder of them (``str`` or ``Path``), once per plugin."""
    from pathlib import Path

    def register(path: Any) -> None:
        if not isinstance(path, (str, Path)) or not str(path).strip():
            raise TypeError(f"world {path!r} is not a path (a str or pathlib.Path of a world file or folder)")
        resolved = Path(path).expanduser().resolve()
        if any(name == str(resolved) for name, _ in found):
            raise ValueError(f"world '{resolved}' is registered twice by plugin '{plugin}'")
        found.append((str(resolved), resolved))
    return register


# ------------------------------------------------------------------ the registry
def _sync() -> None:
    """Follow plugins (un)registered directly through ``pm``; rebuild the registry if anything changed."""
    live = {name: plugin for name, plugin in pm.list_name_plugin() if plugin is not None}
    dirty = _state.registry is None
    kept = [r for r in _state.records if r.plugin is None or live.get(r.name) is r.plugin]
    dirty |= len(kept) != len(_state.records)
    known = {r.name for r in kept if r.plugin is not None}
    for name, plugin in live.items():
        if name not in known:
            rec = _Record(name, "", "", getattr(plugin, "__name__", type(plugin).__module__))
            rec.error = _check_hooks(plugin) or _scan(rec, plugin)
            if rec.error is None:
                rec.plugin = plugin
            else:
                pm.unregister(plugin)
                log.warning("sigcore plugin %s failed to load and is disabled: %s", rec.info().describe(),
                            rec.error)
            kept.append(rec)
            dirty = True
    _state.records = kept
    if dirty:
        _rebuild()


def _rebuild() -> None:
    registry: dict[str, dict[str, Any]] = {kind: {} for kind in KINDS}
    owners: dict[tuple[str, str], _Record] = {}
    infos = []
    for rec in _state.records:
        provides: dict[str, tuple[str, ...]] = {}
        for kind in KINDS:
            names = []
            for name, value in rec.found.get(kind, []) if rec.error is None else []:
                first = owners.get((kind, name))
                if first is None:
                    registry[kind][name] = value
                    owners[kind, name] = rec
                    names.append(name)
                elif registry[kind][name] is not value:
                    log.warning("%s '%s' of sigcore plugin %s is ignored: plugin %s registered it first",
                                kind, name, rec.info().describe(), first.info().describe())
            if names:
                provides[kind] = tuple(names)
        infos.append(rec.info(provides))
    _state.registry = registry
    _state.infos = infos


def _registry(kind: str) -> dict[str, Any]:
    load_plugins()
    assert _state.registry is not None
    return _state.registry[kind]


def _get(kind: str, name: str) -> Any:
    found = _registry(kind)
    if name not in found:
        raise PluginError(kind, name, sorted(found), [i for i in _state.infos if i.error is not None])
    return found[name]


def backends() -> dict[str, type[Backend]]:
    """Registered backend classes by name."""
    return dict(_registry("backend"))


def transports() -> dict[str, type[Transport]]:
    """Registered transport classes by name."""
    return dict(_registry("transport"))


def features() -> dict[str, type[Feature]]:
    """Registered feature classes by name (enabled per world with ``<plugin name=...>``)."""
    return dict(_registry("feature"))


def controllers() -> dict[str, type[Any]]:
    """Registered controller classes by short name (a world attaches one with ``controller="name"``)."""
    return dict(_registry("controller"))


def spawnables() -> dict[str, Spawnable]:
    """Spawnables registered by plugins, by name (``model://NAME``; :mod:`sigcore.world.spawnables` adds the
    folders of ``worlds/models``). Each one's ``origin`` is the plugin's name."""
    return dict(_registry("spawnable"))


def worlds() -> list[tuple[Path, str]]:
    """World files and folders registered by plugins (``sigcore_register_worlds``), each with the plugin's name;
    :mod:`sigcore.world.catalogue` lists them with ``worlds/`` and the command line's."""
    load_plugins()
    assert _state.registry is not None
    owners = {name: info.name for info in _state.infos for name in info.provides.get("world", ())}
    return [(path, owners.get(name, "")) for name, path in _state.registry["world"].items()]


def get_backend(name: str) -> type[Backend]:
    """The backend class called ``name``.

    Raises:
        PluginError: not registered; the message lists the registered backends and the failed plugins.
    """
    return _get("backend", name)


def get_transport(name: str) -> type[Transport]:
    """The transport class called ``name``; :class:`PluginError` listing the valid ones otherwise."""
    return _get("transport", name)


def viewers() -> dict[str, type[Viewer]]:
    """Registered viewer classes by name (``sigcore run --viewer``, ``sigcore view``)."""
    return dict(_registry("viewer"))


def get_viewer(name: str) -> type[Viewer]:
    """The viewer class called ``name``; :class:`PluginError` listing the valid ones otherwise."""
    return _get("viewer", name)


def get_feature(name: str) -> type[Feature]:
    """The feature class called ``name``; :class:`PluginError` listing the valid ones otherwise."""
    return _get("feature", name)


def add_commands(cli: Any) -> None:
    """Call every loaded plugin's ``sigcore_register_commands(cli)``; one that raises is logged by name and
    the others still add theirs."""
    infos = {i.name: i for i in load_plugins()}
    for impl in pm.hook.sigcore_register_commands.get_hookimpls():
        try:
            impl.function(*({"cli": cli}[arg] for arg in impl.argnames))
        except USER_ERRORS as e:
            who = infos[impl.plugin_name].describe() if impl.plugin_name in infos else f"'{impl.plugin_name}'"
            log.warning("sigcore plugin %s: sigcore_register_commands raised %s; its commands are missing", who,
                        describe(e))


def notify(hook: str, **kwargs: Any) -> None:
    """Call world-level event hook ``hook`` (e.g. ``sigcore_simulation_started``) on every plugin, one by one: a
    plugin whose hook raises (or calls ``sys.exit``) is logged by name and the others are still called; the
    simulation goes on."""
    load_plugins()
    for impl in getattr(pm.hook, hook).get_hookimpls():
        try:
            impl.function(**{k: v for k, v in kwargs.items() if k in impl.argnames})
        except USER_ERRORS as e:
            log.error("plugin '%s' raised in %s: %s", impl.plugin_name, hook, describe(e))
            log.debug("traceback of plugin '%s' in %s", impl.plugin_name, hook, exc_info=True)
