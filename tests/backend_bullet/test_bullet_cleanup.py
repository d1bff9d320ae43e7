"""The clean-up task on PyBullet: the scripted robot of the referee plugin does it as on MuJoCo."""

from __future__ import annotations

from pathlib import Path

import pytest

from sigcore.sim import Simulation, run
from sigcore.world import parse_world

ROOT = Path(__file__).parent.parent.parent


@pytest.mark.slow
def test_scripted_cleanup_succeeds_on_bullet() -> None:
    """controller="cleanup.robot" grasps the three items and puts each in its box on PyBullet: 3 x (1000 + 50)
    points, succeeded, no collision, wrong-box or outside penalty (about 25 s wall time)."""
    referee = pytest.importorskip("sigcore_referee")
    world = parse_world(ROOT / "worlds" / "cleanup.xml")
    sim = Simulation(world, "bullet", {"robot_000": "cleanup.robot"})
    run(sim, duration=300.0)
    ref = sim.features["referee"]
    assert isinstance(ref, referee.Referee)
    kinds = [(e.kind, e.text) for e in ref.events]
    assert ref.result == "succeeded" and ref.score == 3 * (1000 + 50), kinds
    assert not [k for k, _ in kinds if k in ("collision", "wrong_box", "outside")]
