"""No exception ends a transport thread: a raising callback on the action node's executor is logged once and the
executor keeps serving (the transport runs in this process, the client in another)."""

from __future__ import annotations

import logging
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, client_process, last_json, start_in_process  # noqa: E402

pytestmark = pytest.mark.ros2


def test_a_raising_executor_callback_is_logged_once_and_the_executor_serves_on(
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """Two requests whose callback raises: one ERROR naming the node and the exception, none of the thread's
    end; the action node's and the main node's parameter services answer afterwards."""
    sim, transport, env = start_in_process(monkeypatch, WORLD)

    def boom(request: Any, response: Any) -> Any:
        raise KeyError("planted by the test")

    try:
        raising = [s for s in transport._action_node.services if s.srv_name.endswith("/get_parameter_types")]
        assert len(raising) == 1
        raising[0].callback = boom
        with caplog.at_level(logging.WARNING, logger="sigcore.ros2"):
            with client_process(env, "raising.py") as proc:
                while proc.poll() is None:  # this thread is the simulation thread: serve the main node
                    transport.service(0.05)
                out, err = proc.communicate(timeout=5)
    finally:
        transport.stop()
    assert proc.returncode == 0, err[-3000:]
    result = last_json(out)
    assert result["raising"] == [False, False]  # no answer, but no end of the executor either
    assert result["/sigcore_actions"] == result["/sigcore"] == ["use_sim_time", "start_type_description_service"]
    errors = [r for r in caplog.records if r.levelno == logging.ERROR]
    assert len(errors) == 1, [r.getMessage() for r in errors]
    assert "sigcore_actions raised KeyError" in errors[0].getMessage()
    summary = [r.getMessage() for r in caplog.records if "refusals/failures suppressed" in r.getMessage()]
    assert len(summary) == 1 and "of sigcore_actions (KeyError)" in summary[0]  # the second one, counted
