"""Contact events through the simulation, on every backend: debounce, reset, wheels and casters on the floor."""

from __future__ import annotations

import numpy as np
import pytest
from conformance_worlds import ROBOT, robot

from sigcore import plugins
from sigcore.agent.events import CollisionEvent
from sigcore.sim import Simulation
from sigcore.sim.contacts import CONTACT_HOLD, hold_steps

BOX = '<object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 0.05"/>'


def _listen(sim: Simulation) -> list[CollisionEvent]:
    events: list[CollisionEvent] = []
    sim.events.subscribe("collision", events.append)
    return events


def _lift_for(sim: Simulation, steps: int) -> None:
    """Hold the box 0.3 m above its resting pose for ``steps`` steps, then put it back (touching again at once)."""
    box = sim.agent("box")
    rest = box.position()
    box.set_gravity_mode(False)
    box.set_position(rest + np.array([0.0, 0.0, 0.3]))
    box.set_velocity(np.zeros(3))
    sim.step(steps)
    assert not any(t[0] == "box" for t in sim.contact_triples())
    box.set_position(rest)
    box.set_gravity_mode(True)
    sim.step(1)
    assert ("box", "main", "ground") in sim.contact_triples()


def test_contact_episode_ends_only_after_the_hold_time(make_world, simulate) -> None:
    """A box lifted off the floor for one step less than CONTACT_HOLD and put back starts no new event; lifted for
    exactly CONTACT_HOLD it starts one (the hold is counted in steps, so this is exact)."""
    sim = simulate(make_world(BOX))
    events = _listen(sim)
    sim.step(100)
    assert [(e.agent, e.part, e.other) for e in events] == [("box", "main", "ground")]
    hold = hold_steps(CONTACT_HOLD, sim.dt)
    assert hold == 50
    events.clear()
    _lift_for(sim, hold - 1)
    sim.step(100)
    assert events == []
    _lift_for(sim, hold)
    assert [(e.agent, e.part, e.other) for e in events] == [("box", "main", "ground")]
    assert events[0].time == pytest.approx(sim.time)
    sim.step(100)
    assert len(events) == 1


def test_reset_closes_every_episode(make_world, simulate) -> None:
    """After reset, a contact of the initial state starts a new event on the next step, even if it was apart for
    less than the hold time (reset closes episodes) or never apart at all."""
    sim = simulate(make_world(BOX + '<object name="ball" shape="sphere" size="0.05" pose="1 0 0.05"/>'))
    events = _listen(sim)
    sim.step(100)
    box = sim.agent("box")
    box.set_gravity_mode(False)
    box.set_position(box.position() + np.array([0.0, 0.0, 0.3]))
    sim.step(5)
    events.clear()
    sim.reset()
    sim.step(1)
    assert sorted((e.agent, e.other) for e in events) == [("ball", "ground"), ("box", "ground")]
    sim.step(100)
    assert len(events) == 2


def test_wheels_and_casters_on_the_floor_are_no_events(make_world, simulate) -> None:
    """A robot driving forward, back and turning gets no event for its wheels or casters on the floor, while the
    raw contacts (collision_state) show them touching; its rolling parts are the drive's wheel links (named by
    the joints' children, here wheel_l / wheel_r) and the links named *caster*."""
    sim = simulate(make_world(robot()))
    events = _listen(sim)
    bot = sim.robot("bot")
    assert sim.entities.rolling_parts("bot") == {"wheel_l", "wheel_r", "caster_f", "caster_b"}
    for left, right in ((5.0, 5.0), (-5.0, -5.0), (-4.0, 4.0), (6.0, 2.0), (0.0, 0.0)):
        bot.set_wheel_velocity(left, right)
        sim.step(round(0.6 / sim.dt))
    assert bot.collision_state("wheel_l") and bot.collision_state("wheel_r")
    assert {p for e, p, o in sim.contact_triples() if e == "bot" and o == "ground"} >= {"wheel_l", "wheel_r"}
    assert [e for e in events if e.agent == "bot"] == []


@pytest.mark.parametrize(("casters", "eventful"), [("caster_f", {"caster_b"}), ("", {"caster_f", "caster_b"})])
def test_casters_attribute_replaces_the_name_rule(make_world, simulate, casters: str, eventful: set[str]) -> None:
    """With <drive casters="...">, only the listed links are casters: a caster link left out of the list touching
    the floor is an ordinary collision (one event), and the wheels stay quiet."""
    xml = ROBOT.format(pose="0 0 0 0 0 0", extra="").replace('separation="0.4"/>',
                                                             f'separation="0.4" casters="{casters}"/>')
    sim = simulate(make_world(xml))
    events = _listen(sim)
    sim.step(round(1.0 / sim.dt))
    touching = {p for e, p, o in sim.contact_triples() if e == "bot" and o == "ground"}
    assert {(e.part, e.other) for e in events if e.agent == "bot"} == {(p, "ground") for p in eventful & touching}
    assert eventful & touching, touching  # the bot rests on at least one caster left out of the list
    assert len([e for e in events if e.agent == "bot"]) == len(eventful & touching)


def test_a_wheel_against_a_wall_is_an_event(make_world, simulate) -> None:
    """Only floor contacts of rolling parts are left out: a wheel touching a static box beside it is one event."""
    wall = '<object name="wall" shape="box" size="0.6 0.1 0.3" static="true" pose="0 0.269 0.15"/>'
    sim = simulate(make_world(robot() + wall))
    events = _listen(sim)
    sim.step(round(0.5 / sim.dt))
    assert [(e.agent, e.part, e.other) for e in events if e.agent == "bot"] == [("bot", "wheel_l", "wall")]


def test_contacts_are_read_only_while_someone_listens(make_world, backend_name: str) -> None:
    """With no on_collision controller and no collision observer, stepping never asks the backend for contacts
    (the step loop stays cheap); once an observer listens, it asks at most once per step (MuJoCo's compiled loop
    only when they changed) and the event is there."""
    base = plugins.get_backend(backend_name)

    class Counting(base):  # type: ignore[misc, valid-type]
        calls = 0

        def contacts(self) -> frozenset[tuple[int, int]]:
            Counting.calls += 1
            return super().contacts()

    sim = Simulation(make_world(BOX), Counting())
    sim.step(20)
    assert Counting.calls == 0
    events = _listen(sim)
    sim.step(20)
    assert 1 <= Counting.calls <= 20 and len(events) == 1
