"""Controllers: the SIGVerse lifecycle in PEP 8 names.

Subclass :class:`Controller` and override what you need. The simulation checks once which callbacks a controller
overrides and never calls the others, so an empty controller costs nothing per step.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ..isolation import USER_ERRORS, describe
from .events import CollisionEvent, Message
from .exceptions import ControllerError

if TYPE_CHECKING:
    from .handle import SimObj

CALLBACKS = ("on_init", "on_action", "on_collision", "on_recv_msg")


class Controller:
    """Base class of every controller. ``ctx`` is the agent's handle (:class:`~sigcore.agent.handle.SimObj`)."""

    def on_init(self, ctx: SimObj) -> None:
        """Called once, before the first step."""

    def on_action(self, ctx: SimObj) -> float:
        """Called at time 0 and then again after the number of simulated seconds it returns [s]."""
        return 1.0

    def on_collision(self, ctx: SimObj, event: CollisionEvent) -> None:
        """Called once when one of the agent's parts starts touching another entity (a contact episode; wheels and
        casters on the floor are none: ``sigcore.sim.contacts``)."""

    def on_recv_msg(self, ctx: SimObj, msg: Message) -> None:
        """Called for each text message sent to this agent."""


def overridden(controller: Controller) -> frozenset[str]:
    """Names of the lifecycle callbacks that ``controller``'s class overrides."""
    cls = type(controller)
    return frozenset(name for name in CALLBACKS if getattr(cls, name) is not getattr(Controller, name))


def resolve_controller(spec: str, registered: dict[str, type]) -> type:
    """Find a controller class by registered name, ``package.module:Class`` or ``package.module.Class``.

    Raises:
        ControllerError: not found, not importable, or not a :class:`Controller`; the message lists registered
            names.
    """
    if spec in registered:
        cls = registered[spec]
    else:
        module_name, sep, attr = spec.partition(":")
        if not sep:
            module_name, _, attr = spec.rpartition(".")
        if not module_name or not attr:
            raise ControllerError(_unknown(spec, registered))
        try:
            module = importlib.import_module(module_name)
        except ImportError as e:
            raise ControllerError(f"cannot import module '{module_name}' for controller '{spec}': {e}. "
                                  + _unknown(spec, registered)) from None
        except USER_ERRORS as e:  # the user's module raised (or called sys.exit) while importing
            raise ControllerError(f"importing '{module_name}' for controller '{spec}' raised {describe(e)}") \
                from None
        try:
            cls = getattr(module, attr)
        except AttributeError:
            raise ControllerError(f"module '{module_name}' has no '{attr}' (controller '{spec}')") from None
    if not (isinstance(cls, type) and issubclass(cls, Controller)):
        raise ControllerError(f"controller '{spec}' is {cls!r}, not a subclass of sigcore.agent.Controller")
    return cls


def _unknown(spec: str, registered: dict[str, type]) -> str:
    names = ", ".join(sorted(registered)) or "none registered"
    return (f"controller '{spec}' is neither a registered name ({names}) nor a dotted path "
            "'package.module:Class'")
