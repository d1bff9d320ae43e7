"""Controllers used by the core tests: they record what the simulation calls on them."""

from __future__ import annotations

from sigcore.agent import CollisionEvent, Controller, Message, SimObj

CALLS: list[tuple[str, str, float]] = []
"""(agent, callback, time) of every call to a :class:`Tracker`, in order (module-level so world-attached
controllers can be inspected)."""


class Tracker(Controller):
    """Records every lifecycle call; ``on_action`` returns ``period``."""

    period = 0.1

    def __init__(self) -> None:
        self.events: list[CollisionEvent] = []
        self.messages: list[Message] = []

    def on_init(self, ctx: SimObj) -> None:
        CALLS.append((ctx.name, "on_init", ctx.time))

    def on_action(self, ctx: SimObj) -> float:
        CALLS.append((ctx.name, "on_action", ctx.time))
        return self.period

    def on_collision(self, ctx: SimObj, event: CollisionEvent) -> None:
        CALLS.append((ctx.name, "on_collision", ctx.time))
        self.events.append(event)

    def on_recv_msg(self, ctx: SimObj, msg: Message) -> None:
        CALLS.append((ctx.name, "on_recv_msg", ctx.time))
        self.messages.append(msg)


class ActionOnly(Controller):
    """Overrides only ``on_action``."""

    def __init__(self) -> None:
        self.count = 0

    def on_action(self, ctx: SimObj) -> float:
        self.count += 1
        return 0.05


class Raising(Controller):
    """Raises in ``on_action`` at its third call."""

    def __init__(self) -> None:
        self.count = 0

    def on_action(self, ctx: SimObj) -> float:
        self.count += 1
        if self.count == 3:
            raise RuntimeError("boom")
        return 0.01


class Greeter(Controller):
    """Sends a message to ``moderator`` and broadcasts one at init."""

    def on_init(self, ctx: SimObj) -> None:
        ctx.send_msg("moderator", "hello moderator")
        ctx.broadcast_msg("hello all")


class BadPeriod(Controller):
    """Returns a non-number from ``on_action``."""

    def on_action(self, ctx: SimObj) -> float:
        return "soon"  # type: ignore[return-value]
