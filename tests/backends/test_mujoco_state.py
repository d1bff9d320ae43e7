"""MuJoCo only: poses read from ``qpos`` after a step, and an engine instability reported once."""

from __future__ import annotations

import numpy as np
import pytest


def test_pose_after_step_matches_qpos(make_world, build_mujoco) -> None:
    """After a step, get_pose describes the integrated state (not the state before the step)."""
    b = build_mujoco(make_world('<object name="o" shape="sphere" size="0.1" pose="0 0 5"/>'))
    b.set_velocity("o", linear=np.array([3.0, 0.0, 0.0]))
    b.step()
    np.testing.assert_allclose(b.get_pose("o")[0], b.data.qpos[0:3], atol=1e-15)
    assert b.get_pose("o")[0][0] == pytest.approx(3.0 * 0.002)


def test_an_engine_instability_is_reported_once(make_world, build_mujoco, caplog: pytest.LogCaptureFixture) -> None:
    """A torque that makes MuJoCo's accelerations blow up (it then resets its state) is logged once as a warning
    naming the entity, and counted each time it happens; a calm world logs nothing."""
    import logging

    b = build_mujoco(make_world('<object name="pebble" shape="sphere" size="0.01" mass="0.001" pose="0 0 0.5"/>'))
    with caplog.at_level(logging.WARNING, logger="sigcore.backend"):
        for _ in range(128):  # calm: nothing
            b.step()
        assert b.instabilities == 0 and not caplog.records
        for _ in range(3):
            b.apply_wrench("pebble", None, np.zeros(3), np.array([1e12, 1e12, 0.0]))
            for _ in range(256):
                b.step()
    assert b.instabilities >= 1
    warnings = [r.getMessage() for r in caplog.records if "unstable" in r.getMessage()]
    assert len(warnings) == 1 and "object 'pebble'" in warnings[0], warnings
