"""The default /clock policy (docs/ros2.md, "The /clock policy"): far fewer messages than steps, but every stamped
state message and scan has its time on /clock first, and the last step's time is on /clock once paused."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosproc import WORLD, start_sim

pytestmark = pytest.mark.ros2

DT_NS = 2_000_000  # the test world's timestep


def test_clock_policy(tmp_path: Path) -> None:
    """Playing at 4x real time for 2 s of simulated time: under half the steps reach /clock (the wall-time limit
    is 200 per second, about 100 state steps besides), every odom, /tf and scan stamp is a /clock stamp, and the
    time of the step the simulation paused at is the last /clock."""
    sim = start_sim(tmp_path, WORLD, "--paused", "--factor", "4")
    try:
        r = sim.client("clock_policy.py", timeout=90)
    finally:
        sim.stop()
    assert r["play"] == 1 and r["pause"] == 1, r  # RESULT_OK
    steps = (r["end"] - r["start"]) // DT_NS
    assert steps >= 1000, steps
    clock = set(r["clock"])
    assert r["clock_messages"] < steps / 2, (r["clock_messages"], steps)
    for topic in ("odom", "tf", "scan"):
        stamps = [s for s in r[topic] if s > r["start"]]
        assert stamps, f"no {topic} message while playing"
        ahead = sorted(set(stamps) - clock)
        assert not ahead, f"{topic} stamps never published on /clock: {ahead[:5]}"
    assert r["clock"][-1] == r["end"], (r["clock"][-5:], r["end"])
