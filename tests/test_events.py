"""The event hub (``sigcore.sim.events``, issue 29 item 1): typed channels, subscriptions owned and cancelled, a
feature's failure on any channel contained and detached from every channel, a world's subscriptions gone with it,
and no observer list left outside the hub."""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pydantic import Field

import sigcore
from sigcore import plugins
from sigcore.feature import Feature, FeatureConfig
from sigcore.publish import Publication, PublicationSink
from sigcore.sim import Simulation
from sigcore.sim.events import CHANNELS, Channel, Events, Reset, Subscription
from sigcore.sim.features import FeatureOwner
from sigcore.world import parse_world
from sigcore.world.resources import SpawnRequest

ROOT = Path(__file__).parent.parent
DATA = Path(__file__).parent / "data" / "sim"

# ---------------------------------------------------------------------------------------------- the hub on its own


def test_subscribers_are_called_in_order_and_cancel_and_detach_end_them() -> None:
    """Delivery follows subscription order; cancel ends one (twice is harmless); detach(owner) ends an owner's on
    every channel and says how many."""
    events = Events()
    seen: list[tuple[str, object]] = []
    first = events.subscribe("step", lambda p: seen.append(("first", p)))
    events.subscribe("step", lambda p: seen.append(("second", p)), owner="me")
    events.subscribe("reset", lambda p: seen.append(("reset", p)), owner="me")
    events.emit("step", 1)
    first.cancel()
    first.cancel()
    events.emit("step", 2)
    assert seen == [("first", 1), ("second", 1), ("second", 2)] and not first.active
    assert events.detach("me") == 2 and events.subscriptions() == () and not events.wanted("step")
    events.emit("step", 3)
    events.emit("reset", Reset(True))
    assert len(seen) == 3


def test_owned_by_gives_subscriptions_their_owner() -> None:
    """Inside ``owned_by`` a subscription made without an owner is the scope's; an explicit owner wins; outside,
    ``owner_of`` decides."""
    events = Events(owner_of=lambda fn: "found")
    with events.owned_by("feature"):
        a = events.subscribe("scan", print)
        b = events.subscribe("scan", print, owner="explicit")
    c = events.subscribe("scan", print)
    assert (a.owner, b.owner, c.owner) == ("feature", "explicit", "found")
    assert events.subscriptions("scan", owner="feature") == (a,)


def test_unknown_channel_and_non_callable_are_refused_naming_what_is_valid() -> None:
    events = Events()
    with pytest.raises(ValueError, match=r"no event channel 'stepp'; channels: step, collision, .*reset, input"):
        events.subscribe("stepp", print)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="must be callable, got int"):
        events.subscribe("step", 3)  # type: ignore[arg-type]


def _feature_f_fails(calls: list[str], contained: list[Subscription], channel: Channel) -> Events:
    """A hub whose containment detaches the failing owner (what the simulation does when it disables a feature),
    with owner "f"'s two subscribers on ``channel``: the first raises."""
    def contain(subscription: Subscription, exc: BaseException) -> bool:
        contained.append(subscription)
        events.detach(subscription.owner)
        return True

    def broken(_: object) -> None:
        calls.append("broken")
        raise RuntimeError("boom")

    events = Events(contain)
    events.subscribe(channel, broken, owner="f")
    events.subscribe(channel, lambda _: calls.append("f's second"), owner="f")
    return events


def test_step_subscribers_are_called_after_the_multiples_of_their_every() -> None:
    """``every=3`` is called after steps 3, 6, 9...; ``set_every(0)`` pauses it, ``set_every(1)`` makes it every
    step; steps_free counts the steps up to the next one a subscriber is due at."""
    events = Events()
    seen: dict[str, list[int]] = {"each": [], "third": []}
    sub = events.subscribe("step", lambda step: seen["third"].append(step), every=3)
    assert sub.every == 3
    assert events.steps_free(0, 100) == 3 and events.steps_free(4, 100) == 2 and events.steps_free(4, 1) == 1
    for step in range(1, 10):
        events.emit_step(step, step)
    assert seen["third"] == [3, 6, 9]
    sub.set_every(0)
    assert events.steps_free(9, 100) == 100
    events.emit_step(12, 12)
    assert seen["third"] == [3, 6, 9]
    events.subscribe("step", lambda step: seen["each"].append(step))
    assert events.steps_free(12, 100) == 1
    sub.set_every(1)
    events.emit_step(13, 13)
    assert seen == {"each": [13], "third": [3, 6, 9, 13]}


def test_a_bad_every_is_refused_naming_what_is_valid() -> None:
    events = Events()
    for bad in (-1, 2.5, True, "3"):
        with pytest.raises(ValueError, match=r"every must be a whole number of steps of at least 0 \(0: not called\), "
                                             r"got"):
            events.subscribe("step", print, every=bad)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="every applies to the 'step' channel only, not to 'scan'"):
        events.subscribe("scan", print, every=5)
    sub = events.subscribe("step", print)
    with pytest.raises(ValueError, match="got -2"):
        sub.set_every(-2)
    assert sub.every == 1


def test_a_contained_failure_of_a_step_subscriber_skips_only_its_owner_and_respects_every() -> None:
    """A failing step subscriber is contained like on any channel: its owner is detached; the subscribers after
    it that are due are still called in that delivery, those not due are not."""
    calls: list[str] = []
    events = _feature_f_fails(calls, [], "step")
    events.subscribe("step", lambda _: calls.append("every 2"), owner="g", every=2)
    events.subscribe("step", lambda _: calls.append("every 3"), owner="g", every=3)
    events.emit_step(None, 2)
    events.emit_step(None, 3)
    assert calls == ["broken", "every 2", "every 3"]


def test_a_contained_failure_detaches_its_owner_even_from_the_delivery_in_progress() -> None:
    """When the containment detaches the failing owner, the owner's later subscribers are not called, even in the
    delivery in progress; the others are."""
    calls: list[str] = []
    contained: list[Subscription] = []
    events = _feature_f_fails(calls, contained, "collision")
    events.subscribe("collision", lambda _: calls.append("other"), owner="g")
    events.emit("collision", None)
    events.emit("collision", None)
    assert calls == ["broken", "other", "other"] and [s.owner for s in contained] == ["f"]


def test_the_same_subscriber_twice_is_called_twice_and_a_failure_finds_its_own_place() -> None:
    """One callable subscribed twice hears each event twice; when its second subscription's owner fails (the first
    is another owner's), the delivery goes on after the second, not after the first."""
    calls: list[str] = []

    def hears(payload: str) -> None:
        calls.append(payload)

    def raises_once_detached(payload: str) -> None:
        calls.append("raiser")
        raise RuntimeError(payload)

    def contain(subscription: Subscription, exc: BaseException) -> bool:
        events.detach(subscription.owner)
        return True

    events = Events(contain)
    events.subscribe("message", hears, owner="a")
    events.subscribe("message", raises_once_detached, owner="b")
    events.subscribe("message", hears, owner="c")
    events.emit("message", "x")
    events.emit("message", "y")
    assert calls == ["x", "raiser", "x", "y", "y"]


def test_an_uncontained_failure_propagates_and_stops_that_delivery() -> None:
    """No containment (no feature owns the subscriber): the error reaches the emitter's caller."""
    calls: list[str] = []
    events = Events(lambda s, e: False)
    events.subscribe("step", lambda _: 1 / 0)
    events.subscribe("step", lambda _: calls.append("after"))
    with pytest.raises(ZeroDivisionError):
        events.emit("step", None)
    assert calls == []


def test_subscribing_during_a_delivery_takes_effect_from_the_next_event() -> None:
    events = Events()
    calls: list[int] = []

    def adds(payload: int) -> None:
        calls.append(payload)
        events.subscribe("step", lambda p: calls.append(-p))

    events.subscribe("step", adds)
    events.emit("step", 1)
    assert calls == [1]
    events.emit("step", 2)
    assert calls == [1, 2, -2]


# ------------------------------------------------------------------------------ features failing on every channel

class GrumpyConfig(FeatureConfig):
    raise_on: str = Field(description="the channel whose events it raises on")


class Grumpy(Feature):
    """Subscribes to every channel in its constructor, counts each event, raises on the ``raise_on`` channel."""

    name = "grumpy"
    config_model = GrumpyConfig

    def __init__(self, sim: Simulation, config: GrumpyConfig) -> None:
        self.raise_on = config.raise_on
        self.seen: Counter[str] = Counter()
        for channel in CHANNELS:
            sim.events.subscribe(channel, self._counter(channel))

    def _counter(self, channel: Channel) -> object:
        def count(_: object) -> None:
            self.seen[channel] += 1
            if channel == self.raise_on:
                raise RuntimeError(f"grumpy about {channel}")
        return count


class GrumpyPlugin:
    @sigcore.hookimpl
    def sigcore_register_features(self, register: object) -> None:
        register(Grumpy)  # type: ignore[operator]


WORLD = """<world name="grumpy" timestep="0.002">
  <robot name="bot" urdf="{urdf}" pose="0 0 0 0 0 0">
    <drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.36"/>
    <lidar name="scan" link="laser_link" beams="30" range="0.05 8" rate="10"/>
    <camera name="head" link="base_link" pose="0.1 0 0.4" width="32" height="24" rate="10" type="rgb"/>
  </robot>
  <object name="ball" shape="sphere" size="0.05" mass="0.3" pose="1 1 0.2"/>
  <agent name="moderator"/>
  <plugin name="grumpy" raise_on="{channel}"/>
</world>
"""


@pytest.fixture
def grumpy(fresh_plugins: None) -> Iterator[None]:
    plugins.register_plugin(GrumpyPlugin(), name="grumpy_events")
    yield


def grumpy_sim(tmp_path: Path, channel: str) -> Simulation:
    path = tmp_path / "grumpy.xml"
    path.write_text(WORLD.format(urdf=DATA / "minibot.urdf", channel=channel))
    return Simulation(parse_world(path), "mujoco")


def provoke(sim: Simulation, channel: str) -> None:
    """Make the simulation emit at least one event of ``channel``."""
    if channel == "message":
        sim.send_msg("moderator", "bot", "hi")
        sim.step(1)
    elif channel in ("step", "scan", "collision", "camera"):
        sim.step(150)  # the ball lands within 0.2 s; the lidar and the camera are due at step 50
        sim.cameras.settle()
    elif channel in ("entities", "scene"):
        [name] = sim.entities.spawn([SpawnRequest(resource='<object shape="box" size="0.1 0.1 0.1" pose="0 2 0.05"/>',
                                         name="crate", allow_renaming=True)])
        assert isinstance(name, str)
    elif channel == "reset":
        sim.reset(despawn=False)
    elif channel == "input":
        sim.inputs.note("message", sender="moderator", to="bot", text="hi")
    elif channel == "control":
        sim.control.pause()
    elif channel == "world":
        sim.worlds.unload()


@pytest.mark.parametrize("channel", CHANNELS)
def test_a_feature_raising_on_any_channel_is_disabled_and_detached_from_every_channel(
        grumpy: None, tmp_path: Path, channel: str) -> None:
    """A feature whose subscriber of ``channel`` raises is disabled once (``<channel> observer``) and has no
    subscription left on any channel; nothing of it is called again while the run goes on."""
    sim = grumpy_sim(tmp_path, channel)
    feature = sim.features["grumpy"]
    assert isinstance(feature, Grumpy)
    guard = sim.features  # the world's (an unload replaces it)
    assert {s.channel for s in sim.events.subscriptions(owner=FeatureOwner("grumpy"))} == set(CHANNELS)
    provoke(sim, channel)
    assert feature.seen[channel] >= 1
    assert [(f.feature, f.where) for f in guard.failures] == [("grumpy", f"{channel} observer")]
    assert f"grumpy about {channel}" in guard.failures[0].error
    assert sim.events.subscriptions(owner=FeatureOwner("grumpy")) == ()
    if channel == "world":
        return  # unloaded: nothing more to provoke
    before = Counter(feature.seen)
    for other in ("message", "step", "entities", "reset", "input", "control"):
        provoke(sim, other)
    assert feature.seen == before and len(guard.failures) == 1


def test_a_world_unload_detaches_what_its_features_and_parts_subscribed(grumpy: None, tmp_path: Path) -> None:
    """Unloading a world detaches its features' subscriptions and its own parts' (the description topics, the
    publication sources); a library user's stays and hears the next world."""
    sim = grumpy_sim(tmp_path, "nothing")
    sim.publications.connect(_Sink())  # a sink connects: the agents' publication sources subscribe
    mine = sim.events.subscribe("step", lambda s: None)
    world_s = [s for s in sim.events.subscriptions() if s is not mine]
    assert {s.channel for s in world_s} >= {"scan", "scene", "message", "collision"}
    assert {str(s.owner) for s in world_s} == {"FeatureOwner(name='grumpy')", "<the world's parts>"}
    sim.worlds.unload()
    assert not any(s.active for s in world_s) and mine.active
    sim.worlds.load(parse_world(DATA / "world.xml"))
    assert mine.active and mine in sim.events.subscriptions("step")
    assert sim.events.subscriptions("scene")  # the new world's description topics


class _Sink(PublicationSink):
    """A publication sink that wants everything and keeps nothing."""

    def declare(self, publication: Publication) -> None:
        pass

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        pass

    def wants(self, publication: Publication) -> bool:
        return True


# ------------------------------------------------------------------------------------------ no list outside the hub

OBSERVER_LIST = re.compile(
    r"\b(?:add|remove)_step_observer\b|\b(?:step|collision|message|scan|camera|entity|world|reset)_observers\b"
    r"|inputs\.listeners\b|scene\.add_observer\b|OBSERVER_LISTS")


def test_nothing_outside_the_hub_keeps_the_simulations_observer_lists() -> None:
    """The simulation's eight observer lists, ``add/remove_step_observer``, the input listeners and the scene's
    observers are gone: no code, example or document under the project uses them; every event goes through
    ``sim.events``."""
    found = []
    for folder in ("sigcore", "plugins", "examples", "docs", "bench"):
        for path in sorted((ROOT / folder).rglob("*")):
            if path.suffix not in (".py", ".md") or ".egg-info" in str(path):
                continue
            for number, line in enumerate(path.read_text().splitlines(), 1):
                if OBSERVER_LIST.search(line):
                    found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert found == []
    sim_lists = [name for name in vars(Simulation(parse_world(DATA / "world.xml"), "mujoco"))
                 if name.endswith(("observers", "listeners"))]
    assert sim_lists == []
