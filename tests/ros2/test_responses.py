"""Service responses, and simulate_steps' goal and result responses, whose client's response reader is not matched
(yet) are kept and sent again, not dropped silently by rmw (the transport runs in this process, the client in another;
see sigcore_ros2/responses.py and sigcore_ros2/action.py)."""

from __future__ import annotations

import logging
import time

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, client_process, last_json, start_in_process, tell_stop  # noqa: E402

pytestmark = pytest.mark.ros2


def test_an_undeliverable_response_is_tried_again_then_dropped_with_a_warning(
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """A client whose response reader never matches (incompatible durability, a real rmw timeout on each send): its
    requests' responses are kept and tried again (more tries than requests), then dropped after GIVE_UP with a
    warning naming the service; nothing stays kept, and no service() call of the simulation thread is blocked by the
    retries for more than 1 s (stated margin: each round stops at its first timeout of 0.1 s)."""
    from sigcore_ros2 import responses

    monkeypatch.setattr(responses, "GIVE_UP", 1.0)
    sim, transport, env = start_in_process(monkeypatch, WORLD)
    sends: list[int] = []
    requests: list[int] = []
    original, first = responses._send, responses.Responder.send

    def counting(*args: object) -> bool:
        sends.append(1)
        return original(*args)

    def answering(*args: object) -> None:
        requests.append(1)
        first(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(responses, "_send", counting)
    monkeypatch.setattr(responses.Responder, "send", answering)
    longest = 0.0
    try:
        with caplog.at_level(logging.WARNING, logger="sigcore.ros2"):
            told = False
            with client_process(env, "unmatched_call.py", stdin=True) as proc:
                end = None
                # past GIVE_UP and a round for the last request (3 s), and on until a response was dropped, at most
                # 30 s after the client ended (a loaded machine delays the requests' arrival and the rounds)
                while end is None or time.monotonic() < end[0] or (not _dropped(caplog) and time.monotonic() < end[1]):
                    t = time.monotonic()  # this thread is the simulation thread
                    transport.service(0.05)
                    longest = max(longest, time.monotonic() - t)
                    if not told and len(requests) >= 4:  # 4 requests arrived (discovery done): the client stops
                        tell_stop(proc)
                        told = True
                    if end is None and proc.poll() is not None:
                        end = (time.monotonic() + 3.0, time.monotonic() + 30.0)
                out, err = proc.communicate(timeout=5)
        kept = len(transport._receiver.responder._unsent)
    finally:
        transport.stop()
    assert proc.returncode == 0, err[-3000:]
    result = last_json(out)
    assert requests, "no request of the client arrived within 60 s"
    assert result["answered"] is False  # the client could never receive it: the case is real
    dropped = _dropped(caplog)
    assert dropped, [r.getMessage() for r in caplog.records]
    assert all(m.startswith("/get_simulation_state: ") for m in dropped), dropped
    assert requests and len(sends) > len(requests), (len(sends), len(requests))  # tried again, not dropped at once
    assert kept == 0  # nothing is kept past GIVE_UP
    assert longest < 1.0, longest


def _dropped(caplog: pytest.LogCaptureFixture, says: str = "a response was dropped") -> list[str]:
    """The warnings saying a response was dropped (``says``)."""
    return [r.getMessage() for r in caplog.records if says in r.getMessage()]


@pytest.mark.parametrize("unmatched, accepted", [("result", True), ("goal", None)])
def test_an_undeliverable_action_response_is_tried_again_then_dropped_with_a_warning(
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture, unmatched: str,
        accepted: bool | None) -> None:
    """A simulate_steps client one of whose response readers never matches (incompatible durability, a real rmw
    failure on each send): of get_result (its goal is accepted, its result cannot be delivered), or of send_goal
    (what a client that sent its goal before the simulator discovered it meets for a while, here for good: the
    goal arrives and is accepted, the acceptance cannot be delivered). The response is tried again (more than one
    try), then dropped after GIVE_UP with a warning naming the action and the response; the goal takes its 5 steps
    either way (its client asked for them); the simulation thread is never blocked by the tries for more than 1 s
    (stated margin: they run on the action node's executor thread)."""
    from sigcore_ros2 import responses

    monkeypatch.setattr(responses, "GIVE_UP", 1.0)
    sim, transport, env = start_in_process(monkeypatch, WORLD)
    says = f"a {unmatched} response was dropped"
    longest = 0.0
    try:
        with caplog.at_level(logging.WARNING, logger="sigcore.ros2"):
            with client_process(env, "unmatched_result.py", unmatched, stdin=True) as proc:
                end = time.monotonic() + 120.0  # a bound only: discovery on a loaded machine
                while (not _dropped(caplog, says) or sim.step_count < 5) and time.monotonic() < end \
                        and proc.poll() is None:
                    t = time.monotonic()  # this thread is the simulation thread
                    transport.service(0.05)
                    if sim.control.take_step():
                        sim.step()
                    longest = max(longest, time.monotonic() - t)
                tell_stop(proc)
                out, err = proc.communicate(timeout=30)
    finally:
        transport.stop()
    assert proc.returncode == 0, err[-3000:]
    result = last_json(out)
    assert result == {"accepted": accepted, "result": False}, result  # the case is real
    assert sim.step_count == 5  # the goal ran
    dropped = _dropped(caplog, says)
    assert len(dropped) == 1 and dropped[0].startswith("/simulate_steps: "), dropped
    tries = int(dropped[0].split(" tries")[0].rsplit("(", 1)[1])
    assert tries >= 2, dropped  # tried again, not dropped at once
    assert longest < 1.0, longest
