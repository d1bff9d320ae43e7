"""The ``hello.greeter`` controller."""

from __future__ import annotations

from sigcore.agent import Controller, Message, SimObj


class Greeter(Controller):
    """Greets every other agent at start, counts the messages it receives, and acts every ``period`` seconds.

    Attributes:
        received: Number of messages received.
        last: Text of the last message received ("" before any).
        actions: Number of ``on_action`` calls.
    """

    period = 0.5
    """Time between two ``on_action`` calls [s]."""

    def __init__(self) -> None:
        self.received = 0
        self.last = ""
        self.actions = 0

    def on_init(self, ctx: SimObj) -> None:
        """Say hello to every other agent."""
        ctx.broadcast_msg(f"hello from {ctx.name}")

    def on_action(self, ctx: SimObj) -> float:
        """Count the call; be called again in ``period`` seconds."""
        self.actions += 1
        return self.period

    def on_recv_msg(self, ctx: SimObj, msg: Message) -> None:
        """Count the message."""
        self.received += 1
        self.last = msg.content
