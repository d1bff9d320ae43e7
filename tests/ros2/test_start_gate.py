"""sigcore run --wait-for: the simulation holds at t = 0 until the named topics have their peers."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")

from rosproc import WORLD, start_sim, wait_until  # noqa: E402

from sigcore.sim.startgate import WaitFor  # noqa: E402

pytestmark = pytest.mark.ros2


def test_a_node_started_2_s_late_receives_clock_from_zero(tmp_path: Path) -> None:
    """With --wait-for /clock, a /clock subscriber started 2 s after the simulation is up gets t = 0 first, then
    increasing times; the simulation said on stderr what it waits for."""
    sim = start_sim(tmp_path, WORLD, "--realtime", "--wait-for", "/clock")
    try:
        time.sleep(2.0)
        out = sim.client("clock_from_start.py")
        assert wait_until(lambda: "every awaited topic has its peers: playing" in sim.output(), 5.0), sim.output()
        log = sim.output()
    finally:
        sim.stop()
    assert out["first"] == 0.0, out
    assert out["monotonic"] and out["last"] >= 1.0, out
    assert log.count("waiting for 1 subscriber of /clock (0 so far)") == 1, log  # once (a reminder after 10 s)
    assert "paused until the --wait-for topics have their peers" in log


def test_wait_timeout_plays_without_peers(tmp_path: Path) -> None:
    """--wait-timeout 1 plays after 1 s of wall time with a warning naming what is missing."""
    sim = start_sim(tmp_path, WORLD, "--realtime", "--wait-for", "/bot/cmd_vel=2", "--wait-timeout", "1")
    try:
        assert wait_until(lambda: "--wait-timeout 1 s" in sim.output(), 15.0), sim.output()
        out = sim.client("clock_from_start.py")
        log = sim.output()
    finally:
        sim.stop()
    assert "2 publishers of /bot/cmd_vel (0 so far)" in log
    assert out["last"] >= 1.0  # it plays


@pytest.mark.parametrize(("text", "parsed"), [("/clock", WaitFor("/clock", 1)), ("clock=3", WaitFor("/clock", 3)),
                                              ("/robot_000/cmd_vel=1", WaitFor("/robot_000/cmd_vel", 1))])
def test_wait_for_parses_topic_and_count(text: str, parsed: WaitFor) -> None:
    """TOPIC[=N] gives the full topic name and N (default 1)."""
    assert WaitFor.parse(text) == parsed


@pytest.mark.parametrize(("text", "match"), [("/clock=0", "N >= 1"), ("/clock=x", "not an integer"),
                                             ("a b", "not TOPIC or TOPIC=N")])
def test_wait_for_refuses_malformed_text(text: str, match: str) -> None:
    """A malformed --wait-for says what is valid."""
    with pytest.raises(ValueError, match=match):
        WaitFor.parse(text)
