"""Hostile ROS 2 clients: a seeded fuzz campaign on every endpoint, the nodes' own services, malformed parameters.

Each test starts its own simulation process (paused, real-time pace, so the campaign's step requests stay short)
and runs the clients in separate processes (tests/ros2/clients/).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import ALL_AGENTS, WORLD, start_sim  # noqa: E402
from test_transport import expected_endpoints  # noqa: E402

from sigcore.api import api_table  # noqa: E402

pytestmark = [pytest.mark.ros2, pytest.mark.slow]

SEED = 17
REQUESTS = 1200
"""Requests of the campaign (service calls and published messages) [requests]: every endpoint first, then random ones
(seeded: the same campaign every run; 2000 took about 40 s, 1200 about 25 s)."""

LOG_LIMIT = 200_000
"""The simulation's whole log after the campaign stays under this [bytes]."""

CALL_TIMEOUT = 10.0
"""Every service call must be answered within this [s] (the client's CALL_TIMEOUT)."""

DT = 0.002
OK, PARAMETER_BOOL = 1, 1
BUILTIN = ("describe_parameters", "get_parameters", "get_parameter_types", "list_parameters", "set_parameters",
           "set_parameters_atomically", "get_type_description")


def test_fuzz_campaign_every_endpoint_answers_and_the_log_stays_small(tmp_path: Path) -> None:
    """1200 seeded hostile requests on every service and topic: every call is answered within 10 s, no traceback
    is logged, the log stays under 200 kB, and afterwards parameters, reset, positions, time and stepping are
    right."""
    topics, services = expected_endpoints()
    commands = tuple(e.suffix for e in api_table() if e.direction == "subscribe") + ("/cmd_vel",)
    expected = tmp_path / "expected.json"
    expected.write_text(json.dumps({"services": sorted(services),
                                    "topics": sorted(t for t in topics if t.endswith(commands))}))
    sim = start_sim(tmp_path, WORLD, "--paused", "--realtime", *ALL_AGENTS)
    try:
        out = sim.client("fuzz_campaign.py", str(SEED), str(REQUESTS), str(expected), timeout=240)
        alive = sim.alive()
        log = sim.output()
    finally:
        sim.stop()
    assert out["requests"] >= REQUESTS
    assert not out["unanswered"], f"no answer within {CALL_TIMEOUT} s: {out['unanswered'][:20]} {out['detail']}"
    assert out["slowest"] < CALL_TIMEOUT
    missing = set(services) - set(out["calls"])
    assert not missing, f"services never called (not discovered?): {sorted(missing)[:10]}"
    for node in ("/sigcore", "/sigcore_actions"):
        assert {f"{node}/{name}" for name in BUILTIN} <= set(out["calls"])
    assert len(out["published"]) >= 100 and "/bot/cmd_vel" in out["published"]
    assert alive, log[-3000:]
    assert "Traceback" not in log, log[log.index("Traceback") - 500:][:5000]
    assert len(log.encode()) < LOG_LIMIT, f"{len(log.encode())} bytes of log; the first 3000:\n{log[:3000]}"
    after = out["after"]
    assert after["use_sim_time"] == [[PARAMETER_BOOL, True]]
    assert after["parameters"] == ["start_type_description_service", "use_sim_time"]
    assert after["pause"] in (OK, 101) and after["reset"] == OK  # 101: already paused
    assert after["wall"] == pytest.approx({"x": 3.0, "y": 0.0, "z": 0.5}, abs=1e-6)
    cube = after["cube"]
    assert cube["success"] is True
    assert [cube["pos_x"], cube["pos_y"], cube["pos_z"]] == pytest.approx([0.6, 0.5, 0.03], abs=2e-3)
    t0, t1 = after["times"]
    assert after["step"] == OK and t1 == pytest.approx(t0 + 100 * DT, abs=1e-9)
    assert after["action"] == OK and after["time_after_action"] == pytest.approx(t1 + 20 * DT, abs=1e-9)


def test_parameter_services_answer_and_malformed_requests_are_refused(tmp_path: Path) -> None:
    """/sigcore and /sigcore_actions parameter services answer (use_sim_time true on /sigcore, read-only);
    unknown, mistyped and malformed SetParameters get refusals naming the problem; the action still works."""
    sim = start_sim(tmp_path, WORLD, "--paused", "--realtime", *ALL_AGENTS)
    try:
        out = sim.client("params.py", timeout=120)
        log = sim.output()
    finally:
        sim.stop()
    for node, sim_time in (("/sigcore", True), ("/sigcore_actions", False)):
        got = out[node]
        assert got["list"] == ["use_sim_time", "start_type_description_service"], got
        assert got["use_sim_time"] == [[PARAMETER_BOOL, sim_time]]
        assert got["get"] == []  # one unknown name: rclpy answers with no values
        assert got["describe"] == ["use_sim_time"] and got["types"] == [PARAMETER_BOOL]
        assert got["type_description"][0] is False and "RIHS01_" in got["type_description"][1]
        assert got["set_use_sim_time"][0][0] is False and "read-only" in got["set_use_sim_time"][0][1]
        assert got["set_unknown"][0][0] is False and "undeclared" in got["set_unknown"][0][1]
        assert got["set_wrong_type"][0][0] is False
        bad_type, empty, huge = got["set_malformed"]
        assert bad_type == [False, bad_type[1]] and "value type 200 is not a ParameterType; valid: 0 not_set" \
            in bad_type[1]
        assert empty == [False, "a parameter name cannot be empty"]
        assert huge[0] is False and "(100000 characters)" in huge[1] and len(huge[1]) < 400
        assert got["set_atomically_malformed"][0] is False and "value type 77" in got["set_atomically_malformed"][1]
        assert got["use_sim_time_after"] == [[PARAMETER_BOOL, sim_time]]
    assert out["accepted"] and out["action"] == OK  # the action node's executor still serves
    assert "Traceback" not in log
