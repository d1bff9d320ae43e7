"""Controlling the simulation through simulation_interfaces (own simulation process: it ends quitting)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, SimProcess, start_sim, wait_until  # noqa: E402

pytestmark = pytest.mark.ros2

OK, ALREADY = 1, 101
STOPPED, PLAYING, PAUSED = 0, 1, 2
DT = 0.002


def test_pause_step_reset_stop_play_quit(sim_proc: SimProcess) -> None:
    """Paused /clock stands still; step N and simulate_steps N advance it exactly; reset restores poses
    without moving /clock back; stop, play and quit work."""
    out = sim_proc.client("control.py", timeout=120)
    assert set(out["features"]) == {0, 1, 2, 3, 4, 5, 6, 8, 9, 10, 11, 12, 13, 14, 20, 22, 23, 24, 25, 26, 31, 32,
                                    33, 40, 41, 42, 43, 44, 45, 50}  # nothing unsupported announced
    assert out["initial_state"] == PLAYING
    assert (out["pause"], out["paused_state"], out["pause_again"]) == (OK, PAUSED, ALREADY)
    c0, c1 = out["clock_still"]
    assert c1 == c0
    assert out["step"] == OK and out["after_step"] == pytest.approx(c0 + 100 * DT, abs=1e-9)
    assert out["action"] == OK and out["after_action"] == pytest.approx(c0 + 600 * DT, abs=1e-9)
    assert out["action_feedback"] and max(out["action_feedback"]) <= 500
    assert out["set_ball"] == OK and out["ball_set"] == pytest.approx([0.5, -1.5, 1.0], abs=1e-6)
    assert out["reset"] == OK and out["ball_reset"] == pytest.approx([-1.0, 1.0, 0.05], abs=2e-3)
    assert out["after_reset"] >= out["after_action"]  # time never goes back
    assert out["reset_time"] == 0  # RESULT_FEATURE_UNSUPPORTED
    assert out["entities_b"] == ["bot", "ball"] and out["entities_trash"] == ["cube"]
    assert out["states"]["cube"] == pytest.approx([0.6, 0.5], abs=1e-3)
    assert (out["stop"], out["stopped_state"], out["play"]) == (OK, STOPPED, OK)
    before, after = out["after_play"]
    assert after > before
    assert out["quit"] == OK
    assert wait_until(lambda: not sim_proc.alive(), 15.0), "the simulation did not quit"


def test_started_paused_waits_for_play(tmp_path: Path) -> None:
    """`sigcore run --paused --transport ros2`: PAUSED at time 0 until set_simulation_state PLAYING."""
    sim = start_sim(tmp_path, WORLD, "--paused", "--realtime")
    try:
        out = sim.client("paused.py")
    finally:
        sim.stop()
    assert out["state"] == PAUSED and out["still"] == 0.0
    assert out["play"] == OK and out["played"] > 0.1


def test_long_simulate_steps_goals_leave_the_action_services_answering(tmp_path: Path) -> None:
    """MAX_RUNNING long simulate_steps goals run (paused, real-time pace: each would take 2000 s); one more is
    rejected; meanwhile get_result of an unknown goal and the action node's parameter services answer within 5 s
    (stated margin: they need only a free executor thread, which the goals never take); each goal can be canceled,
    and afterwards a new goal is accepted and succeeds."""
    from sigcore_ros2.action import MAX_RUNNING

    sim = start_sim(tmp_path, WORLD, "--paused", "--realtime")
    try:
        out = sim.client("busy_actions.py", str(MAX_RUNNING), timeout=120)
        log = sim.output()
    finally:
        sim.stop()
    assert out["accepted"] == MAX_RUNNING
    assert out["last_answered"] and not out["last_accepted"]
    assert "at most 8 at once" in log
    assert out["unknown_status"] == 0 and out["unknown_result_s"] < 5.0  # STATUS_UNKNOWN
    assert out["parameters_answered"] and out["parameters_s"] < 5.0
    assert out["canceled"] == MAX_RUNNING and out["ended"] == MAX_RUNNING
    assert out["accepted_after"] and out["after_result"] == OK
