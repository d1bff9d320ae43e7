"""Clean-up rules for collisions: one penalty per contact episode with furniture, a wall or the floor."""

from __future__ import annotations

from pathlib import Path

import pytest
from referee_worlds import BOXES, ITEMS, ROBOT, make_sim, run_for
from sigcore_referee import Referee
from sigcore_referee.collisions import default_floor_parts

from sigcore.sim import Simulation

FAR_BOXES = BOXES.replace('pose="0 0 0"', 'pose="3 3 0"').replace('pose="1 0 0"', 'pose="3 -3 0"')


def _sim(tmp_path: Path, attributes: str = 'rules="cleanup"') -> Simulation:
    """sigbot at the origin facing +x, a wall whose face is 0.30 m behind it; boxes and items far away."""
    return make_sim(tmp_path, ROBOT + FAR_BOXES + ITEMS, attributes)


def _referee(sim: Simulation) -> Referee:
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    return ref


def _penalties(sim: Simulation) -> list[str]:
    return [e.text for e in _referee(sim).events if e.kind == "collision"]


def _drive(sim: Simulation, speed: float, seconds: float) -> None:
    sim.robot("robot_000").set_base_velocity(speed, 0.0)
    run_for(sim, seconds)


def test_continuous_contact_is_one_episode(tmp_path: Path) -> None:
    """Backing into the wall and pushing against it for 3 s costs one penalty."""
    sim = _sim(tmp_path)
    _drive(sim, -0.2, 5.0)
    assert ("robot_000", "base_link", "wall_west") in sim.contact_triples()
    assert _penalties(sim) == ["robot_000 hit wall_west (wall) with base_link"]
    assert _referee(sim).score == -100


def test_two_contacts_with_a_gap_are_two_episodes(tmp_path: Path) -> None:
    """Hitting the wall, pulling away for more than the debounce time and hitting it again costs two penalties."""
    sim = _sim(tmp_path)
    _drive(sim, -0.2, 2.5)
    _drive(sim, 0.3, 1.0)
    _drive(sim, 0.0, 0.5)
    assert not any(t[0] == "robot_000" and t[2] == "wall_west" for t in sim.contact_triples())
    _drive(sim, -0.3, 2.0)
    assert len(_penalties(sim)) == 2 and _referee(sim).score == -200


def test_contact_gap_shorter_than_debounce_is_the_same_episode(tmp_path: Path) -> None:
    """With debounce="5" the same two contacts 1.5 s apart are one episode."""
    sim = _sim(tmp_path, 'rules="cleanup" debounce="5"')
    _drive(sim, -0.2, 2.5)
    _drive(sim, 0.3, 1.0)
    _drive(sim, -0.3, 2.0)
    assert len(_penalties(sim)) == 1


def test_standing_on_wheels_and_casters_is_not_a_floor_collision(tmp_path: Path) -> None:
    """Wheels and casters touch the ground all the time: no penalty while driving around."""
    sim = _sim(tmp_path)
    _drive(sim, 0.3, 2.0)
    assert _penalties(sim) == []
    assert default_floor_parts(sim, "robot_000") == {"wheel_l_link", "wheel_r_link", "caster_front_link",
                                                     "caster_back_link"}


def test_other_parts_on_the_floor_are_one_floor_collision(tmp_path: Path) -> None:
    """A robot lying on the floor (several parts touching it) costs one floor penalty."""
    sim = _sim(tmp_path)
    robot = sim.robot("robot_000")
    robot.set_position([1.5, 0.0, 0.3])
    robot.set_axis_and_angle([1.0, 0.0, 0.0], 1.5708)
    run_for(sim, 2.0)
    penalties = _penalties(sim)
    assert len(penalties) == 1 and "robot_000 touched the floor with" in penalties[0]


def test_floor_can_be_switched_off(tmp_path: Path) -> None:
    """floor="false": lying on the floor is not penalised."""
    sim = _sim(tmp_path, 'rules="cleanup" floor="false"')
    robot = sim.robot("robot_000")
    robot.set_position([1.5, 0.0, 0.3])
    robot.set_axis_and_angle([1.0, 0.0, 0.0], 1.5708)
    run_for(sim, 2.0)
    assert _penalties(sim) == []


@pytest.mark.parametrize(("attributes", "expected"), [
    ('rules="cleanup" collision="-250"', -250),
    ('rules="cleanup" collision_tags="furniture"', 0),
])
def test_points_and_tags_are_configurable(tmp_path: Path, attributes: str, expected: int) -> None:
    """The penalty and which tags count come from the plugin element."""
    sim = _sim(tmp_path, attributes)
    _drive(sim, -0.2, 3.0)
    assert _referee(sim).score == expected
