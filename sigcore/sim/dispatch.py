"""Controller dispatch: which controller runs when, and what happens when one raises."""

from __future__ import annotations

import heapq
import logging
import math
import traceback
from dataclasses import dataclass, replace
from time import perf_counter
from typing import TYPE_CHECKING

from ..agent.controller import Controller, overridden
from ..agent.events import CollisionEvent, Message
from ..isolation import USER_ERRORS, CallbackBudget, describe

if TYPE_CHECKING:
    from ..agent.handle import SimObj

log = logging.getLogger("sigcore")


@dataclass(frozen=True)
class ControllerFailure:
    """A controller raised (or misbehaved) and was disabled.

    Attributes:
        agent: The agent whose controller failed.
        callback: ``on_init``, ``on_action``, ``on_collision`` or ``on_recv_msg``.
        time: Simulation time [s].
        error: ``Type: message`` of the exception.
        traceback: The formatted traceback.
    """

    agent: str
    callback: str
    time: float
    error: str
    traceback: str


@dataclass(frozen=True)
class SlowCallbacks:
    """An agent's controller callbacks that took longer than the budget.

    Attributes:
        agent: The agent.
        count: How many calls took longer than the budget.
        longest: The longest of them [s] (wall-clock).
        callback: The callback of the longest (``on_action``...).
        time: Simulation time of the first [s].
        budget: The budget in force [s].
    """

    agent: str
    count: int
    longest: float
    callback: str
    time: float
    budget: float


class Dispatcher:
    """Calls each controller's overridden callbacks at the right steps; disables a controller that raises (or calls
    ``sys.exit``), and reports (or disables, see :class:`CallbackBudget`) one whose callback takes too long."""

    def __init__(self, timestep: float) -> None:
        self._dt = timestep
        self._controllers: dict[str, tuple[Controller, SimObj]] = {}
        self._action: list[tuple[int, int, str]] = []  # heap of (due step, order, agent)
        self._order: dict[str, int] = {}
        self.collision_listeners: dict[str, Controller] = {}
        self.message_listeners: dict[str, Controller] = {}
        self._init: list[str] = []
        self.failures: list[ControllerFailure] = []
        self.slow: dict[str, SlowCallbacks] = {}
        """Agents whose callbacks took longer than :attr:`budget`, by agent."""
        self.budget = CallbackBudget()

    @property
    def budget(self) -> CallbackBudget:
        """The wall-clock budget of one callback (default :data:`CALLBACK_BUDGET`, reported, not disabled)."""
        return self._budget

    @budget.setter
    def budget(self, budget: CallbackBudget) -> None:
        self._budget = budget
        self._limit = budget.seconds if budget.seconds > 0 else math.inf

    def add(self, handle: SimObj, controller: Controller) -> None:
        """Attach ``controller`` to the agent of ``handle``; only its overridden callbacks will be called."""
        name = handle.name
        self._controllers[name] = (controller, handle)
        self._order[name] = len(self._order)
        callbacks = overridden(controller)
        if "on_init" in callbacks:
            self._init.append(name)
        if "on_action" in callbacks:
            heapq.heappush(self._action, (0, self._order[name], name))
        if "on_collision" in callbacks:
            self.collision_listeners[name] = controller
        if "on_recv_msg" in callbacks:
            self.message_listeners[name] = controller

    def remove(self, agent: str) -> None:
        """Detach the controller of ``agent`` (deleted while running); nothing if it has none."""
        self._controllers.pop(agent, None)
        self.collision_listeners.pop(agent, None)
        self.message_listeners.pop(agent, None)
        self._init = [name for name in self._init if name != agent]

    def controller(self, agent: str) -> Controller | None:
        """The agent's controller, or None if it was disabled."""
        entry = self._controllers.get(agent)
        return entry[0] if entry else None

    def init(self, time: float) -> None:
        """Call every ``on_init`` once, in world order."""
        for name in self._init:
            self._call(name, "on_init", time)
        self._init = []

    @property
    def has_actions(self) -> bool:
        """Whether any controller has an ``on_action`` scheduled (the step loop skips :meth:`actions` otherwise)."""
        return bool(self._action)

    @property
    def next_action(self) -> int | None:
        """The step the next ``on_action`` is due at (None: none scheduled)."""
        return self._action[0][0] if self._action else None

    def actions(self, step: int, time: float) -> None:
        """Call every ``on_action`` due at ``step`` and schedule its next call."""
        heap = self._action
        while heap and heap[0][0] <= step:
            _, order, name = heapq.heappop(heap)
            if name not in self._controllers:
                continue
            period = self._call(name, "on_action", time)
            if name not in self._controllers:
                continue
            if not isinstance(period, int | float) or isinstance(period, bool) or not math.isfinite(period) \
                    or period < 0:
                self._fail(name, "on_action", time,
                           f"on_action must return the next period in [s] (a finite number >= 0), got {period!r}",
                           "")
                continue
            heapq.heappush(heap, (step + max(1, round(period / self._dt)), order, name))

    def collision(self, event: CollisionEvent) -> None:
        """Deliver a collision event to its agent's controller, if it listens."""
        if event.agent in self.collision_listeners:
            self._call(event.agent, "on_collision", event.time, event)

    def message(self, msg: Message) -> None:
        """Deliver a message to its recipient's controller, if it listens."""
        if msg.to in self.message_listeners:
            self._call(msg.to, "on_recv_msg", msg.time, msg)

    def _call(self, name: str, callback: str, time: float, *args: object) -> object:
        controller, handle = self._controllers[name]
        start = perf_counter()
        try:
            result = getattr(controller, callback)(handle, *args)
        except USER_ERRORS as e:  # sys.exit in a controller disables it too; Ctrl-C is the user's
            self._fail(name, callback, time, describe(e), traceback.format_exc())
            return None
        spent = perf_counter() - start
        if spent > self._limit:
            self._slow(name, callback, time, spent)
        return result

    def _slow(self, name: str, callback: str, time: float, spent: float) -> None:
        budget = self._budget.seconds
        seen = self.slow.get(name)
        if seen is None:
            self.slow[name] = SlowCallbacks(name, 1, spent, callback, time, budget)
            log.warning("controller of agent '%s' took %.3f s of wall time in %s at t=%.3f s, over the callback "
                        "budget of %g s: the whole simulation waited for it (sigcore run --callback-budget S, "
                        "--disable-slow-controllers)", name, spent, callback, time, budget)
        else:
            longest = spent > seen.longest
            self.slow[name] = replace(seen, count=seen.count + 1, longest=max(spent, seen.longest),
                                      callback=callback if longest else seen.callback)
        if self._budget.disable:
            self._fail(name, callback, time, f"took {spent:.3f} s of wall time, over the callback budget of "
                       f"{budget:g} s", "")

    def _fail(self, name: str, callback: str, time: float, error: str, tb: str) -> None:
        failure = ControllerFailure(name, callback, time, error, tb)
        self.failures.append(failure)
        log.error("controller of agent '%s' failed in %s at t=%.3f s and is disabled: %s", name, callback, time,
                  error)
        self._controllers.pop(name, None)
        self.collision_listeners.pop(name, None)
        self.message_listeners.pop(name, None)
