"""State with one owner: grasps, modes and owners each kept by one class, changed through its methods, reset."""

from __future__ import annotations

import pytest

from sigcore.sim import Simulation
from sigcore.sim.grasps import Grasps


def test_grasps_keep_both_directions_consistent() -> None:
    """hold/release keep hand -> object and object -> hand in step; a second grasp of either is refused."""
    g = Grasps()
    g.hold("bot", "hand", "cube")
    assert g.holding("bot", "hand") == "cube" and g.held_by("cube") == ("bot", "hand") and g.is_held("cube")
    with pytest.raises(ValueError, match="already in a grasp"):
        g.hold("bot", "hand", "ball")
    with pytest.raises(ValueError, match="already in a grasp"):
        g.hold("other", "hand", "cube")
    assert g.release("bot", "other_hand") is None
    assert g.release("bot", "hand") == "cube"
    assert not g.is_held("cube") and g.held_by("cube") is None and len(g) == 0


def test_a_grasp_goes_through_the_simulation_record_and_a_reset_clears_it(sim: Simulation) -> None:
    """RobotObj.grasp/release change sim.entities.grasps only through its methods; reset forgets grasps, owners and
    modes."""
    bot = sim.robot("bot")
    part = "hand_link"
    hand = sim.backend.get_pose("bot", part)[0]
    sim.agent("cube").set_position(hand)
    bot.grasp(part, "cube")
    assert sim.entities.grasps.items() == [("bot", part, "cube")] and sim.agent("cube").is_grasped()
    sim.agent("ball").set_owner("main", "bot")
    sim.entities.set_mode("heavy", "gravity", False)
    assert not sim.entities.mode("heavy", "gravity") and sim.entities.modes("heavy")["gravity"] is False
    sim.entities.modes("heavy")["gravity"] = True  # a copy: changing it changes nothing
    assert not sim.entities.mode("heavy", "gravity")
    sim.reset()
    assert len(sim.entities.grasps) == 0 and not sim.agent("cube").is_grasped()
    assert sim.agent("ball").owner() is None
    assert sim.entities.mode("heavy", "gravity") and not sim.entities.mode("wall", "dynamics")  # the world file's modes


def test_an_unknown_mode_is_refused_with_the_valid_ones(sim: Simulation) -> None:
    """A mode name that does not exist names the valid ones and changes nothing."""
    with pytest.raises(ValueError, match="modes: gravity, dynamics, collision"):
        sim.entities.set_mode("heavy", "magnetism", True)  # type: ignore[arg-type]
    assert sim.entities.modes("heavy") == {"gravity": True, "dynamics": True, "collision": True}
