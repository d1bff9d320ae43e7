"""What the referee does on Simulation.reset() (docs/referee.md, "Reset")."""

from __future__ import annotations

from pathlib import Path

import pytest
from referee_worlds import BOXES, ITEMS, MODERATOR, ROBOT, make_sim, run_for
from sigcore_referee import Referee

from sigcore.api import api_table
from sigcore.api.call import call

ENTRIES = {e.suffix: e for e in api_table()}


def test_simulation_reset_starts_a_new_trial(tmp_path: Path) -> None:
    """After points from a message and a first grasp, sim.reset() puts score, events and result back, restarts the
    time limit from the reset, keeps the service connection, and the first grasp earns its points again."""
    sim = make_sim(tmp_path, BOXES + ITEMS + ROBOT + MODERATOR, 'rules="cleanup" time_limit="5"')
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    assert call(sim, ENTRIES["_connect_to_service"], "moderator_0", {"service_name": "referee"})["connected"]
    assert call(sim, ENTRIES["_send_msg_to_srv"], "moderator_0", {"name": "referee", "msg": "Referee/x/7"})["ok"]
    can = sim.agent("can_0")
    can.set_position((0.0, -1.0, 0.8))
    hand = sim.robot("robot_000").part_position("r_hand_link")
    can.set_dynamics_mode(False)
    can.set_position(hand)
    sim.robot("robot_000").grasp("r_hand_link", "can_0")
    run_for(sim, 3.0)
    assert [e.kind for e in ref.events] == ["message", "grasp"] and ref.score == 57
    sim.reset()
    assert (ref.score, ref.events, ref.result, ref.finished) == (0, [], "running", False)
    assert ref.start_time == sim.time > 0
    assert call(sim, ENTRIES["_send_msg_to_srv"], "moderator_0", {"name": "referee", "msg": "Referee/y/3"})["ok"]
    can.set_dynamics_mode(False)
    can.set_position(sim.robot("robot_000").part_position("r_hand_link"))
    sim.robot("robot_000").grasp("r_hand_link", "can_0")
    run_for(sim, 0.2)
    assert [(e.kind, e.points) for e in ref.events] == [("message", 3), ("grasp", 50)]
    run_for(sim, 4.5)
    assert not ref.finished  # 7.7 s after the start, but 4.7 s after the reset: within the 5 s limit
    run_for(sim, 0.4)
    assert ref.result == "time_limit"
    assert ref.end_time == pytest.approx(ref.start_time + 5.0, abs=0.1)  # the rules look at 10 Hz
