"""The PyBullet arm servos go quiet at rest and take a new load like servos updated every step."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from sigcore_backend_bullet import BulletBackend, servo

from sigcore.world import parse_world

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "backends"))
from conformance_worlds import BOT_URDF, robot, run  # noqa: E402

BOX = '<object name="box" shape="box" size="0.08 0.08 0.02" mass="0.5" pose="3 0 0.01 0 0 0"/>'


def _arm_under_a_dropped_box(tmp_path: Path) -> tuple[BulletBackend, list[bool]]:
    """The bot's arm held horizontal for 1 s, then a 0.5 kg box dropped from 0.6 m onto it, 0.25 m from the
    shoulder; returns the backend after 2 s more and whether the bank was quiet after each step."""
    tmp_path.mkdir(exist_ok=True)
    (tmp_path / "bot.urdf").write_text(BOT_URDF)
    bot = robot(extra=' fixed="true"')
    (tmp_path / "w.xml").write_text(f'<world name="w" timestep="0.002">{bot}{BOX}</world>')
    b = BulletBackend()
    b.build(parse_world(tmp_path / "w.xml"))
    b.set_joint_angle("bot", "shoulder", math.pi / 2)
    run(b, 1.0)
    b.set_pose("box", np.array([0.15, 0.0, 0.6]))
    quiet = []
    for _ in range(1000):
        b.step()
        quiet.append(b._servos["bot"]._quiet)
    return b, quiet


def test_quiet_servo_takes_a_load_like_an_updated_one(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A box landing on an arm whose servos went quiet (no backend call at impact) deflects the shoulder to
    within 2e-4 rad of the angle servos updated every step reach, the spring's sag (2.27 + 0.5 g 0.25) / 200
    within 1 mrad."""
    b, quiet = _arm_under_a_dropped_box(tmp_path / "quiet")
    assert any(quiet[:100]), "the servos never went quiet while the box fell"
    box_z = b.get_pose("box")[0][2]
    assert 0.17 < box_z < 0.2  # resting on the arm
    angle = b.get_joint_angle("bot", "shoulder")
    monkeypatch.setattr(servo, "QUIET_STEPS", 10**9)
    ref, never = _arm_under_a_dropped_box(tmp_path / "updated")
    assert not any(never)
    assert angle == pytest.approx(ref.get_joint_angle("bot", "shoulder"), abs=2e-4)
    assert angle - math.pi / 2 == pytest.approx((2.27 + 0.5 * 9.81 * 0.25) / 200, abs=1e-3)


def test_quiet_arm_wakes_on_a_new_target(tmp_path: Path) -> None:
    """A quiet bank wakes for a new target, which the joint then reaches (within 0.015 rad after 2 s)."""
    b, _ = _arm_under_a_dropped_box(tmp_path)
    run(b, 1.0)
    b.set_joint_target("bot", "elbow", -0.6)
    assert not b._servos["bot"]._quiet
    run(b, 2.0)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(-0.6, abs=0.015)


def test_cleanup_robot_at_rest_is_quiet() -> None:
    """robot_000 standing still in the clean-up world has its arm servos quiet most of the time (> 50 % of
    steps), so an idle arm costs little."""
    from sigcore.sim import Simulation

    sim = Simulation(parse_world(Path(__file__).resolve().parents[2] / "worlds" / "cleanup.xml"), "bullet")
    sim.step(500)
    bank = sim.backend._servos["robot_000"]  # type: ignore[attr-defined]
    quiet = 0
    for _ in range(1000):
        sim.step(1)
        quiet += bank._quiet
    assert quiet > 500
