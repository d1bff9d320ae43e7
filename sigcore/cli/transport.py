"""The transport a command starts (``--transport``, else the default when it can start) and its own arguments: what
follows ``--ros-args`` on ``sigcore run``'s command line, taken out before typer parses the rest and handed to the
transport; and the check that the transport can create every endpoint of a world."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import plugins
from .common import err, fail

if TYPE_CHECKING:
    from ..sim import Simulation
    from ..transport import Transport


def check_endpoints(transport: Transport | None, sim: Simulation) -> None:
    """Refuse (exit 2) a world whose endpoints ``transport`` cannot create: invalid or twice-used names."""
    from ..errors import TransportError

    if transport is None:
        return
    try:
        issues = transport.check(sim)
    except ImportError as e:  # the transport's libraries are missing: it cannot start anyway
        raise fail([f"--transport {transport.name}: cannot plan its endpoints here ({e})"]) from None
    except TransportError as e:  # its arguments do not fit this world (e.g. -p naming an agent it does not have)
        raise fail([f"{TRANSPORT_ARGS}: {e}"]) from None
    if issues:
        raise fail([str(i) for i in issues])


DEFAULT_TRANSPORT = "ros2"
"""The transport ``sigcore run`` starts when none is named and it is installed and can start."""


def pick_transport(name: str | None) -> Transport | None:
    """The transport to start: ``name``, none for ``"none"``, or the default when it can start (else one line)."""
    if name == "none":
        return None
    if name is None:
        try:
            cls = plugins.get_transport(DEFAULT_TRANSPORT)
        except plugins.PluginError as e:  # not installed, or its plugin failed to load (the message says which)
            err.print(f"{e}: running without a transport (--transport none says so and silences this line)",
                      markup=False, soft_wrap=True)
            return None
        reason = cls.unavailable()
        if reason is not None:
            err.print(f"transport '{DEFAULT_TRANSPORT}' cannot start: {reason}; running without a transport "
                      "(--transport none silences this line)", markup=False, soft_wrap=True)
            return None
        return cls()
    try:
        cls = plugins.get_transport(name)
    except plugins.PluginError as e:
        raise fail([f"--transport: {e}; or 'none' for a run without a transport"]) from None
    reason = cls.unavailable()
    if reason is not None:
        raise fail([f"--transport {name}: {reason} (--transport none runs without a transport)"])
    return cls()


TRANSPORT_ARGS = "--ros-args"
"""Everything after this on ``sigcore run``'s command line (up to an optional ``--``) is the transport's."""

_transport_args: list[str] | None = None
"""The arguments after ``--ros-args`` (set by :func:`set_transport_args`; None: none given)."""


def split_transport_args(argv: list[str]) -> tuple[list[str], list[str] | None]:
    """``argv`` without the transport's arguments, and those arguments: everything after ``--ros-args`` up to an
    optional ``--`` (what follows ``--`` is sigcore's again); None when ``--ros-args`` is absent."""
    if TRANSPORT_ARGS not in argv:
        return argv, None
    i = argv.index(TRANSPORT_ARGS)
    rest = argv[i + 1:]
    end = rest.index("--") if "--" in rest else len(rest)
    return argv[:i] + rest[end + 1:], rest[:end]


def set_transport_args(args: list[str] | None) -> None:
    """Keep ``args``, the arguments after ``--ros-args`` (None: none given), for :func:`configure_transport`."""
    global _transport_args
    _transport_args = args


def configure_transport(transport: Transport | None, transport_name: str | None) -> None:
    """Hand the arguments after ``--ros-args`` to the transport (exit 2 if it has none or refuses them)."""
    from ..errors import TransportError

    if _transport_args is None:
        return
    if transport is None:
        why = ("--transport none has no transport to take them" if transport_name == "none" else
               f"the default transport '{DEFAULT_TRANSPORT}' cannot start here (see the line above)")
        raise fail([f"{TRANSPORT_ARGS}: {why}; drop {TRANSPORT_ARGS} or run with a transport"])
    try:
        transport.configure(list(_transport_args))
    except TransportError as e:
        raise fail([f"{TRANSPORT_ARGS}: {e}"]) from None
