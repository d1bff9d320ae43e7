"""The simulation's event hub: every event the core emits travels on one typed channel, to its subscribers.

A subscriber is any callable taking the channel's payload. Who owns it decides what happens when it raises: a
subscription owned by a feature disables that feature (the simulation's containment: every subscription the
feature owns, on every channel, is detached at once, and the run goes on); any other subscriber's error propagates
(a bug of the core, of a transport or of the library user: :func:`sigcore.sim.run` ends the run with it).

==========  ==========================================  ==================================================
channel     payload                                     emitted
==========  ==========================================  ==================================================
step        the :class:`Simulation`                     after every step, or every ``every``-th (keep it cheap)
collision   ``sigcore.agent.events.CollisionEvent``     when a contact episode starts (``sim/contacts.py``)
message     ``sigcore.agent.events.Message``            when a text message is delivered, before a step
scan        ``sigcore.sim.lidar.Scan``                  when a lidar scans, after the step's physics
camera      ``sigcore.sim.camera.CameraFrame``          when a camera image finished rendering
entities    ``sigcore.sim.spawn.EntityChange``          after a spawn or delete, the core's state consistent
scene       ``sigcore.scene.Scene``                     after the scene changed (a spawn, a delete)
world       ``sigcore.sim.spawn.WorldChange``           before a world is unloaded and after one is loaded
reset       :class:`Reset`                              after a reset restored the core's state
input       ``sigcore.sim.inputs.Input``                when a command from outside is noted for replay
control     ``sigcore.sim.control.ControlChange``       when a verb of the run control was done (play, pause...)
==========  ==========================================  ==================================================

A ``step`` subscriber that does not need every step says so with ``every`` (:meth:`Events.subscribe`,
:meth:`Subscription.set_every`): it is called after the steps whose number is a multiple of it, or not at all while
it is 0. While no subscriber wants the next steps, nothing else is due and the backend can, the core takes them in
one call (MuJoCo's compiled loop): a run whose features wake up rarely steps at nearly the engine's speed.

Subscribers of a channel are called in the order they subscribed. Subscribing or detaching while an event is
being delivered takes effect from the next event, except that a subscription detached by a failure is not called
again, even by the delivery in progress.

The hub lasts as long as the simulation (across ``sim.worlds.load``); what a world's parts subscribed
(its features, its publication sources, its description topics) is detached when that world is unloaded.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from typing import Any, Literal, get_args

from ..isolation import USER_ERRORS

Channel = Literal["step", "collision", "message", "scan", "camera", "entities", "scene", "world", "reset", "input",
                  "control"]
CHANNELS: tuple[Channel, ...] = get_args(Channel)

Subscriber = Callable[[Any], object]
Containment = Callable[["Subscription", BaseException], bool]
"""Told that a subscription raised; returns True when that was contained (its owner disabled and detached)."""


@dataclass(frozen=True)
class Reset:
    """The payload of the ``reset`` channel: the core's state was restored (``Simulation.reset``).

    Attributes:
        despawn: Whether spawned entities were deleted and deleted world-file entities brought back.
    """

    despawn: bool


class Subscription:
    """One subscriber on one channel; :meth:`cancel` ends it (idempotent).

    Attributes:
        channel: The channel.
        fn: The subscriber.
        owner: Who owns it (a feature's name, a transport, a world's part), or None.
        active: False once cancelled or detached.
        every: ``step`` only: called after the steps whose number is a multiple of it; 0: not called (1 for the
            other channels).
    """

    __slots__ = ("channel", "fn", "owner", "active", "every", "_events")

    def __init__(self, events: Events, channel: Channel, fn: Subscriber, owner: Hashable | None,
                 every: int = 1) -> None:
        self.channel = channel
        self.fn = fn
        self.owner = owner
        self.active = True
        self.every = _every(channel, every)
        self._events = events

    def set_every(self, every: int) -> None:
        """From the next step on, be called after the steps whose number is a multiple of ``every`` (1: every
        step; 0: none, until set again); ``step`` subscriptions only.

        Raises:
            ValueError: not a whole number of at least 0, or not a ``step`` subscription.
        """
        self.every = _every(self.channel, every)

    def cancel(self) -> None:
        """Stop delivering to :attr:`fn` (no error if already cancelled)."""
        self._events._remove(self)

    def __repr__(self) -> str:
        name = getattr(self.fn, "__qualname__", self.fn)
        return f"Subscription({self.channel!r}, {name!r}, owner={self.owner!r}{'' if self.active else ', cancelled'})"


def _every(channel: Channel, every: int) -> int:
    if isinstance(every, bool) or not isinstance(every, int) or every < 0:
        raise ValueError(f"every must be a whole number of steps of at least 0 (0: not called), got {every!r}")
    if every != 1 and channel != "step":
        raise ValueError(f"every applies to the 'step' channel only, not to '{channel}'")
    return every


class Events:
    """The typed channels of one simulation and their subscribers.

    Args:
        contain: Told when a subscriber raised; True if that is contained (the simulation disables the feature that
            owns it, which detaches it); False re-raises the error to the emitter's caller.
        owner_of: The owner of a subscriber subscribed without one and outside :meth:`owned_by` (the simulation
            finds the feature a bound method belongs to); default: none.
    """

    def __init__(self, contain: Containment | None = None,
                 owner_of: Callable[[Subscriber], Hashable | None] | None = None) -> None:
        self._contain = contain
        self._owner_of = owner_of
        # per channel: the subscribers to call and their subscriptions, index for index (replaced, never mutated:
        # a delivery in progress goes on over the tuples it started with)
        self._lists: dict[str, tuple[tuple[Subscriber, ...], tuple[Subscription, ...]]] = {
            channel: ((), ()) for channel in CHANNELS}
        self._scope: list[Hashable] = []

    # ------------------------------------------------------------------ subscribing
    def subscribe(self, channel: Channel, fn: Subscriber, owner: Hashable | None = None,
                  every: int = 1) -> Subscription:
        """Call ``fn(payload)`` on every event of ``channel`` from now on.

        Args:
            channel: One of :data:`CHANNELS`.
            fn: The subscriber.
            owner: Who owns it; default: the owner of the enclosing :meth:`owned_by`, else ``owner_of(fn)``.
            every: ``step`` only: call it after the steps whose number is a multiple of ``every`` (0: not until
                :meth:`Subscription.set_every`).

        Raises:
            ValueError: ``channel`` is not a channel (lists them); ``fn`` is not callable; ``every`` is not a
                whole number of at least 0, or not 1 on another channel than ``step``.
        """
        if channel not in self._lists:
            raise ValueError(f"no event channel {channel!r}; channels: {', '.join(CHANNELS)}")
        if not callable(fn):
            raise ValueError(f"a subscriber of '{channel}' must be callable, got {type(fn).__name__}")
        if owner is None:
            owner = self._scope[-1] if self._scope else (self._owner_of(fn) if self._owner_of else None)
        subscription = Subscription(self, channel, fn, owner, every)
        fns, subs = self._lists[channel]
        call = partial(fn) if any(f is fn for f in fns) else fn  # unique in the tuple: a failure finds its place
        self._lists[channel] = (fns + (call,), subs + (subscription,))
        return subscription

    @contextmanager
    def owned_by(self, owner: Hashable) -> Iterator[None]:
        """Within this block, subscriptions made without an owner are ``owner``'s (a feature's constructor, a
        world part's set-up)."""
        self._scope.append(owner)
        try:
            yield
        finally:
            self._scope.pop()

    def detach(self, owner: Hashable) -> int:
        """Cancel every subscription of ``owner``, on every channel; returns how many there were."""
        count = 0
        for _, subs in list(self._lists.values()):
            mine = [s for s in subs if s.owner == owner]
            for subscription in mine:
                self._remove(subscription)
            count += len(mine)
        return count

    def _remove(self, subscription: Subscription) -> None:
        if not subscription.active:
            return
        subscription.active = False
        fns, subs = self._lists[subscription.channel]
        keep = [i for i, s in enumerate(subs) if s is not subscription]
        self._lists[subscription.channel] = (tuple(fns[i] for i in keep), tuple(subs[i] for i in keep))

    # ------------------------------------------------------------------ asking
    def subscriptions(self, channel: Channel | None = None, owner: Hashable | None = None) -> tuple[Subscription, ...]:
        """The active subscriptions, of ``channel`` (default: every channel) and of ``owner`` (default: anyone's),
        in delivery order."""
        channels = CHANNELS if channel is None else (channel,)
        return tuple(s for c in channels for s in self._lists[c][1] if owner is None or s.owner == owner)

    def wanted(self, channel: Channel) -> bool:
        """Whether anyone subscribed to ``channel`` (an emitter may skip the work of making a payload)."""
        return bool(self._lists[channel][0])

    def steps_free(self, step: int, limit: int) -> int:
        """After step ``step``, how many more steps may be taken before a ``step`` subscriber is due: the number of
        steps up to and including the next one a subscriber is called after, at most ``limit``."""
        free = limit
        for subscription in self._lists["step"][1]:
            every = subscription.every
            if every == 1:
                return 1
            if every:
                free = min(free, every - step % every)
        return free

    # ------------------------------------------------------------------ emitting
    def emit_step(self, payload: object, step: int) -> None:
        """Deliver ``payload`` on ``step`` after step number ``step``: to the subscribers due at it (``every``)."""
        fns, subs = self._lists["step"]
        if not fns:
            return
        try:
            for fn, subscription in zip(fns, subs):  # noqa: B905 - the same length, made together
                every = subscription.every
                if every == 1 or (every and not step % every):
                    fn(payload)
        except USER_ERRORS as e:
            i = next(k for k, f in enumerate(fns) if f is fn)
            self._failed(subs[i], e)
            rest = [(f, s) for f, s in zip(fns[i + 1:], subs[i + 1:]) if s.every and not step % s.every]  # noqa: B905
            self._deliver_rest(tuple(f for f, _ in rest), tuple(s for _, s in rest), payload)

    def emit(self, channel: Channel, payload: object) -> None:
        """Deliver ``payload`` to every subscriber of ``channel``, in subscription order.

        Raises:
            Exception: what a subscriber raised, when :attr:`contain` did not contain it (no feature owns it); the
                subscribers after it are not called then.
        """
        fns, subs = self._lists[channel]
        if not fns:
            return
        try:  # costs nothing until something raises (Python >= 3.11)
            for fn in fns:
                fn(payload)
        except USER_ERRORS as e:
            i = next(k for k, f in enumerate(fns) if f is fn)
            self._failed(subs[i], e)
            self._deliver_rest(fns[i + 1:], subs[i + 1:], payload)

    def _deliver_rest(self, fns: tuple[Subscriber, ...], subs: tuple[Subscription, ...], payload: object) -> None:
        """Go on with a delivery after a failure: skip what the failure detached."""
        for fn, subscription in zip(fns, subs, strict=True):
            if not subscription.active:
                continue
            try:
                fn(payload)
            except USER_ERRORS as e:
                self._failed(subscription, e)

    def _failed(self, subscription: Subscription, exc: BaseException) -> None:
        if self._contain is None or not self._contain(subscription, exc):
            raise exc
