"""Plugin discovery and the registries of backends, transports, features and controllers."""

from __future__ import annotations

import importlib.metadata
import os
import sys
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import pluggy

from . import hookspecs

if TYPE_CHECKING:
    from .backend import Backend
    from .feature import Feature
    from .transport import Transport

GROUP = "sigcore"
DISABLE_ENV = "SIGCORE_DISABLE_PLUGIN_AUTOLOAD"

hookimpl = pluggy.HookimplMarker("sigcore")
pm = pluggy.PluginManager("sigcore")
pm.add_hookspecs(hookspecs)


@dataclass(frozen=True)
class PluginInfo:
    """An installed plugin: entry-point name, distribution and version, and whether it loaded."""

    name: str
    distribution: str
    version: str
    error: str | None = None


@dataclass
class _State:
    loaded: bool = False
    infos: list[PluginInfo] = field(default_factory=list)


_state = _State()


class PluginError(LookupError):
    """A name that is not registered; the message lists the registered ones."""


def load_plugins() -> list[PluginInfo]:
    """Load every plugin once: entry points of group ``sigcore`` unless ``SIGCORE_DISABLE_PLUGIN_AUTOLOAD`` is set.

    A plugin that fails to import or register is recorded with its error (see :func:`plugin_infos`); the others
    still load. Idempotent.
    """
    if _state.loaded:
        return _state.infos
    _state.loaded = True
    if os.environ.get(DISABLE_ENV):
        return _state.infos
    for ep in importlib.metadata.entry_points(group=GROUP):
        dist = ep.dist
        dname, version = (dist.name, dist.version) if dist is not None else ("?", "?")
        if pm.has_plugin(ep.name):
            continue
        try:
            module = ep.load()
            pm.register(module, name=ep.name)
            pm.check_pending()
        except Exception as e:  # a broken third-party plugin must not stop the others
            if pm.has_plugin(ep.name):
                pm.unregister(name=ep.name)
            message = f"{type(e).__name__}: {e}"
            _state.infos.append(PluginInfo(ep.name, dname, version, message))
            print(f"sigcore: plugin '{ep.name}' ({dname} {version}) failed to load and is disabled: {message}",
                  file=sys.stderr)
            continue
        _state.infos.append(PluginInfo(ep.name, dname, version))
    return _state.infos


def plugin_infos() -> list[PluginInfo]:
    """Every plugin found, loaded or failed (loads them first)."""
    return load_plugins()


def _collect(hook: Any, what: str) -> dict[str, Any]:
    load_plugins()
    found: dict[str, Any] = {}

    def register(*args: Any) -> None:
        if len(args) == 2:
            name, value = args
        else:
            (value,) = args
            name = getattr(value, "name", None)
            if not isinstance(name, str) or not name:
                raise PluginError(f"{what} {value!r} has no 'name' attribute")
        found.setdefault(name, value)

    for impl in hook.get_hookimpls():
        try:
            impl.function(register)
        except Exception as e:
            print(f"sigcore: plugin '{impl.plugin_name}' failed to register {what}s: {type(e).__name__}: {e}",
                  file=sys.stderr)
    return found


def backends() -> dict[str, type[Backend]]:
    """Registered backend classes by name."""
    return _collect(pm.hook.sigcore_register_backends, "backend")


def transports() -> dict[str, type[Transport]]:
    """Registered transport classes by name."""
    return _collect(pm.hook.sigcore_register_transports, "transport")


def features() -> dict[str, type[Feature]]:
    """Registered feature classes by name (enabled per world with ``<plugin name=...>``)."""
    return _collect(pm.hook.sigcore_register_features, "feature")


def controllers() -> dict[str, type[Any]]:
    """Registered controller classes by short name."""
    return _collect(pm.hook.sigcore_register_controllers, "controller")


def get_backend(name: str) -> type[Backend]:
    """The backend class called ``name``.

    Raises:
        PluginError: not registered; the message lists the registered backends and how to install one.
    """
    found = backends()
    if name not in found:
        valid = ", ".join(sorted(found)) or "none installed"
        raise PluginError(f"backend '{name}' is not registered; available: {valid} "
                          f"(install one, e.g. pip install sigcore-backend-{name})")
    return found[name]


def get_transport(name: str) -> type[Transport]:
    """The transport class called ``name``; :class:`PluginError` listing the valid ones otherwise."""
    found = transports()
    if name not in found:
        valid = ", ".join(sorted(found)) or "none installed"
        raise PluginError(f"transport '{name}' is not registered; available: {valid}")
    return found[name]


def reset_for_tests() -> None:
    """Forget loaded plugins (tests that install fake distributions call this)."""
    for name, plugin in list(pm.list_name_plugin()):
        if plugin is not None:
            pm.unregister(name=name)
    _state.loaded = False
    _state.infos = []
