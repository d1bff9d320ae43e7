"""Clean-up rules for trash items: judged where they come to rest, once; the first grasp earns the bonus once."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from referee_worlds import BOXES, ITEMS, MODERATOR, ROBOT, make_sim, run_for
from sigcore_referee import Referee

from sigcore.sim import Simulation
from sigcore.world import WorldError


@pytest.fixture
def sim(tmp_path: Path) -> Simulation:
    """Two trash boxes (box_can at the origin, box_pet at x = 1) and two items on the floor."""
    return make_sim(tmp_path, BOXES + ITEMS + MODERATOR)


def _referee(sim: Simulation) -> Referee:
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    return ref


def _kinds(ref: Referee) -> list[tuple[str, str, int]]:
    return [(e.kind, e.text.split()[0], e.points) for e in ref.events]


def test_items_at_rest_where_they_start_are_not_judged(sim: Simulation) -> None:
    """Nothing happens to items that stay where they are."""
    run_for(sim, 2.0)
    assert _referee(sim).events == [] and _referee(sim).score == 0


def test_dropped_in_the_right_box(sim: Simulation) -> None:
    """An item that comes to rest inside a box sharing one of its tags scores correct_box (+1000), once."""
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 3.0)
    ref = _referee(sim)
    assert _kinds(ref) == [("correct_box", "can_0", 1000)] and ref.score == 1000
    assert ref.events[0].text == "can_0 in box_can"
    assert 0.3 < ref.events[0].time < 1.5  # fell ~0.35 s, then rest_time 0.5 s


def test_dropped_in_the_wrong_box(sim: Simulation) -> None:
    """An item at rest in a box that does not accept it scores wrong_box (-600) and stays scored."""
    sim.entities["can_0"].set_position([1.0, 0.0, 0.6])
    run_for(sim, 2.0)
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])  # moving it on afterwards changes nothing
    run_for(sim, 2.0)
    ref = _referee(sim)
    assert _kinds(ref) == [("wrong_box", "can_0", -600)] and ref.score == -600
    assert "which takes petbottle recyclable" in ref.events[0].text


def test_dropped_outside_records_an_event_without_points(sim: Simulation) -> None:
    """An item at rest outside every box records 'outside' (0 points) and may still be put in a box later."""
    sim.entities["can_0"].set_position([0.5, 0.8, 0.5])
    run_for(sim, 2.0)
    ref = _referee(sim)
    assert _kinds(ref) == [("outside", "can_0", 0)] and ref.score == 0
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 2.0)
    assert _kinds(ref) == [("outside", "can_0", 0), ("correct_box", "can_0", 1000)]


def test_released_above_a_box_that_bounces_out_is_not_counted(sim: Simulation) -> None:
    """An item let go right above the opening but thrown sideways comes to rest outside: no box points."""
    can = sim.entities["can_0"]
    can.set_position([0.0, 0.0, 0.6])
    can.set_velocity([2.0, 0.0, 0.0])
    run_for(sim, 3.0)
    ref = _referee(sim)
    assert can.position()[0] > 0.22  # beyond the box's far wall
    assert _kinds(ref) == [("outside", "can_0", 0)] and ref.score == 0


def test_no_judgement_while_still_moving(sim: Simulation) -> None:
    """An item inside a box is judged only after rest_time at rest: not while it is still falling or settling."""
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    run_for(sim, 0.6)
    assert _referee(sim).events == []


def test_every_item_in_its_box_ends_the_task_succeeded(sim: Simulation) -> None:
    """When every trash item is in its correct box the task ends 'succeeded' with a final 'end' event."""
    sim.entities["can_0"].set_position([0.0, 0.0, 0.6])
    sim.entities["petbottle_1"].set_position([1.0, 0.0, 0.6])
    run_for(sim, 3.0)
    ref = _referee(sim)
    assert ref.finished and ref.result == "succeeded" and ref.succeeded and ref.score == 2000
    assert ref.events[-1].kind == "end" and ref.events[-1].points == 0
    assert ref.summary()["placed"] == 2


def test_one_item_in_a_wrong_box_ends_the_task_failed(sim: Simulation) -> None:
    """When every item is in a box but one in a wrong one, the task ends 'failed' naming it."""
    sim.entities["can_0"].set_position([1.0, 0.0, 0.6])
    sim.entities["petbottle_1"].set_position([1.0, 0.1, 0.7])
    run_for(sim, 3.0)
    ref = _referee(sim)
    assert ref.result == "failed" and not ref.succeeded and ref.score == 400
    assert "wrong box: can_0" in ref.events[-1].text


def test_grasp_bonus_once_per_item(tmp_path: Path) -> None:
    """The first grasp of a trash item earns +50; releasing and grasping it again earns nothing more."""
    sim = make_sim(tmp_path, ROBOT + BOXES.replace('pose="0 0 0"', 'pose="3 3 0"').replace('pose="1 0 0"',
                                                                                           'pose="3 -3 0"') + ITEMS)
    robot = sim.robot("robot_000")
    ref = _referee(sim)
    for _ in range(2):
        sim.entities["can_0"].set_position(robot.part_position("l_hand_link"))
        robot.grasp("l_hand_link", "can_0")
        run_for(sim, 0.5)
        assert robot.release("l_hand_link") == "can_0"
        run_for(sim, 1.0)
    assert [(e.kind, e.text, e.points) for e in ref.events if e.kind == "grasp"] == [
        ("grasp", "robot_000 grasped can_0", 50)]
    assert ref.items is not None and ref.items.items["can_0"].grasped
    assert np.linalg.norm(sim.entities["can_0"].position()[:2]) < 0.5  # fell by the robot: 'outside' at most


PLATE = """
  <object name="tray" shape="box" size="0.6 0.6 0.02" static="true" pose="0 0 0.01" tags="trashbox can"/>
  <object name="can_0" shape="cylinder" size="0.033 0.12" mass="0.05" pose="-1 1 0.06" tags="trash can"/>"""


def test_box_inner_from_the_plugin_element(tmp_path: Path) -> None:
    """A trash box that is not a URDF needs box_inner; with it, an item resting in that volume is in the box."""
    with pytest.raises(WorldError, match="cannot find the inner volume of trash box 'tray': it is not a URDF"):
        make_sim(tmp_path, PLATE)
    sim = make_sim(tmp_path, PLATE, 'rules="cleanup" box_inner="-0.3 -0.3 0 0.3 0.3 0.3"')
    sim.entities["can_0"].set_position([0.1, 0.1, 0.3])
    run_for(sim, 2.0)
    assert _kinds(_referee(sim)) == [("correct_box", "can_0", 1000), ("end", "every", 0)]
