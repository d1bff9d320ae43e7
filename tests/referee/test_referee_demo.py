"""The scripted clean-up robot does the whole task on MuJoCo: 3 x (1000 + 50) points, no penalty."""

from __future__ import annotations

import pytest
from referee_worlds import ROOT
from sigcore_referee import Referee

from sigcore.sim import Simulation, run
from sigcore.world import parse_world


@pytest.mark.slow
def test_full_task_scores_every_item_in_its_box_without_penalty() -> None:
    """controller="cleanup.robot" grasps the three items and puts each in its box: 3150 points, succeeded, the
    run stopped by the referee in < 150 simulated seconds, no controller failure."""
    world = parse_world(ROOT / "worlds" / "cleanup.xml")
    assert world.plugin("referee") is not None and world.plugin("referee").config["stop_on_finish"] == "true"
    sim = Simulation(world, "mujoco", {"robot_000": "cleanup.robot"})
    report = run(sim, duration=300.0)
    ref = sim.features["referee"]
    assert isinstance(ref, Referee)
    kinds = [(e.kind, e.text) for e in ref.events]
    assert ref.result == "succeeded" and ref.score == 3 * (1000 + 50), kinds
    assert sorted(t for k, t in kinds if k == "correct_box") == [
        "apple_2 in trashbox_1", "can_0 in trashbox_2", "petbottle_1 in trashbox_0"]
    assert sorted(t for k, t in kinds if k == "grasp") == [
        "robot_000 grasped apple_2", "robot_000 grasped can_0", "robot_000 grasped petbottle_1"]
    assert not [k for k, _ in kinds if k in ("collision", "wrong_box", "outside")]
    assert report.failures == [] and report.sim_time < 150.0
    assert report.summary["referee"]["score"] == 3150  # type: ignore[index]
