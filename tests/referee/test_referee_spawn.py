"""The referee follows entities spawned and deleted while running: spawned trash is scored, spawned trash boxes
take items, deleted items are no longer expected (their events stay). On both backends."""

from __future__ import annotations

from pathlib import Path

import pytest
from referee_worlds import BOXES, ITEMS, MODERATOR, ROOT, make_sim, run_for
from sigcore_referee import Referee

from sigcore.sim import Simulation
from sigcore.world import parse_world
from sigcore.world.resources import SpawnRequest

BACKENDS = ("mujoco", "bullet")
CAN = '<object shape="cylinder" size="0.033 0.12" mass="0.05" graspable="true" tags="trash can"/>'


def _referee(sim: Simulation) -> Referee:
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    return ref


def _spawn(sim: Simulation, request: SpawnRequest) -> str:
    (result,) = sim.entities.spawn([request])
    assert isinstance(result, str), result
    return result


def _events(ref: Referee) -> list[tuple[str, str, int]]:
    return [(e.kind, e.text, e.points) for e in ref.events]


@pytest.fixture(params=BACKENDS)
def backend(request: pytest.FixtureRequest) -> str:
    """Each backend in turn."""
    return str(request.param)


@pytest.fixture
def sim(tmp_path: Path, backend: str) -> Simulation:
    """Two trash boxes (box_can at the origin, box_pet at x = 1) and two items on the floor."""
    return make_sim(tmp_path, BOXES + ITEMS + MODERATOR, backend=backend)


def test_spawned_can_in_the_cleanup_world_is_scored(backend: str) -> None:
    """model://can spawned into worlds/cleanup.xml and put above trashbox_2 (which takes cans) scores +1000 with
    its event, and the referee counts four items."""
    sim = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), backend)
    ref = _referee(sim)
    run_for(sim, 0.2)
    name = _spawn(sim, SpawnRequest(name="can_9", uri="model://can", xyz=(0.0, 0.0, 0.1)))
    run_for(sim, 1.5)  # falls 4 cm onto the floor and settles: where it starts, not 'outside'
    assert ref.events == [] and ref.summary()["items"] == 4
    sim.entities[name].set_position([2.0, -2.2, 0.6])  # above trashbox_2's opening
    run_for(sim, 3.0)
    assert _events(ref) == [("correct_box", "can_9 in trashbox_2", 1000)] and ref.score == 1000
    assert ref.summary()["placed"] == 1 and ref.result == "running"


def test_every_item_spawned_ones_included_ends_succeeded(sim: Simulation) -> None:
    """The task ends 'succeeded' only once the spawned item is in its box too; the summary counts it."""
    ref = _referee(sim)
    name = _spawn(sim, SpawnRequest(name="extra_can", resource=CAN, xyz=(-1.0, -1.0, 0.06)))
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    sim.entities["petbottle_1"].set_position([1.0, 0.0, 0.6])
    run_for(sim, 3.0)
    assert not ref.finished and ref.summary()["placed"] == 2 and ref.summary()["items"] == 3
    sim.entities[name].set_position([0.05, 0.05, 0.6])
    run_for(sim, 3.0)
    assert ref.finished and ref.succeeded and ref.score == 3000
    assert ref.events[-1].text == "every trash item is in its correct box (3)"
    assert ref.summary()["placed"] == 3


def test_spawned_item_landing_in_a_box_is_judged(sim: Simulation) -> None:
    """A trash item spawned above a box is judged where it first comes to rest: in that box (a wrong one here)."""
    ref = _referee(sim)
    _spawn(sim, SpawnRequest(name="can_2", resource=CAN, xyz=(1.0, 0.0, 0.6)))  # box_pet takes no cans
    run_for(sim, 3.0)
    assert _events(ref) == [("wrong_box", "can_2 in box_pet, which takes petbottle recyclable", -600)]


def test_deleted_item_is_no_longer_expected(sim: Simulation) -> None:
    """Deleting an unscored item ends the task once the others are in; a deleted scored item's event stays."""
    ref = _referee(sim)
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 3.0)
    assert _events(ref) == [("correct_box", "can_0 in box_can", 1000)]
    sim.entities.delete(["can_0"])
    run_for(sim, 0.5)
    assert _events(ref) == [("correct_box", "can_0 in box_can", 1000)] and not ref.finished
    sim.entities.delete(["petbottle_1"])
    run_for(sim, 0.5)
    assert not ref.finished  # no item left: nothing to judge, the task is not 'succeeded' by default
    assert ref.summary()["items"] == 0 and ref.score == 1000


def test_deleting_the_last_unscored_item_ends_the_task(sim: Simulation) -> None:
    """With one item in its box, deleting the other (never scored) ends the task 'succeeded'."""
    ref = _referee(sim)
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 3.0)
    sim.entities.delete(["petbottle_1"])
    run_for(sim, 0.5)
    assert ref.finished and ref.succeeded and ref.events[-1].text == "every trash item is in its correct box (1)"


def test_spawned_trash_box_takes_items(sim: Simulation) -> None:
    """model://trashbox spawned with the tag 'burnable' is a box: a spawned burnable item put in it scores +1000;
    a spawned table is furniture for the collision rule."""
    ref = _referee(sim)
    box = _spawn(sim, SpawnRequest(name="box_burn", uri="model://trashbox", xyz=(3.0, 3.0, 0.0), tags=("burnable",)))
    apple = _spawn(sim, SpawnRequest(name="apple_9", resource='<object shape="sphere" size="0.04" mass="0.15" '
                                     'tags="trash burnable"/>', xyz=(-1.0, -1.0, 0.04)))
    table = _spawn(sim, SpawnRequest(name="table_9", uri="model://table", xyz=(-3.0, 3.0, 0.0)))
    assert ref.items is not None and ref.collisions is not None
    assert [b.accepts for b in ref.items.boxes if b.name == box] == [frozenset({"burnable"})]
    assert ref.collisions.penalised[table] == ["furniture"]
    run_for(sim, 1.0)
    sim.entities[apple].set_position([3.0, 3.0, 0.6])
    run_for(sim, 3.0)
    assert _events(ref) == [("correct_box", "apple_9 in box_burn", 1000)]
    sim.entities.delete([table])
    assert table not in ref.collisions.penalised


def test_spawned_robot_is_watched_until_deleted(sim: Simulation) -> None:
    """A spawned model://sigbot is watched by the collision rule, its wheels and casters allowed on the floor;
    deleted, it is forgotten."""
    ref = _referee(sim)
    robot = _spawn(sim, SpawnRequest(name="bot_9", uri="model://sigbot", xyz=(3.0, -3.0, 0.0)))
    assert ref.collisions is not None and robot in ref.collisions.robots
    assert ref.collisions.floor_ok[robot] == {"wheel_l_link", "wheel_r_link", "caster_front_link",
                                              "caster_back_link"}
    run_for(sim, 1.0)  # standing on its wheels and back caster: no floor collision
    assert ref.events == []
    sim.entities.delete([robot])
    assert robot not in ref.collisions.robots and robot not in ref.collisions.floor_ok
