"""Endpoints of agents that come and go (the transport in this process, its client in another): a spawned robot's
request still queued when the robot is deleted is answered with a refusal, and its endpoints leave the transport."""

from __future__ import annotations

import contextlib
import time

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import WORLD, client_process, last_json, ros_env, start_in_process, tell_stop  # noqa: E402
from sigcore_ros2.config import Ros2Config  # noqa: E402
from sigcore_ros2.transport import Ros2Transport  # noqa: E402

from sigcore.sim.simulation import Simulation  # noqa: E402
from sigcore.world import parse_world  # noqa: E402
from sigcore.world.resources import SpawnRequest  # noqa: E402

pytestmark = pytest.mark.ros2

BOX = '<object shape="box" size="0.1 0.1 0.1"/>'


def test_a_queued_request_of_a_deleted_agent_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """A request to a spawned box's service that is queued (not yet served) when the box is deleted gets
    success=false saying the agent was deleted; the box's endpoints are gone from the transport and from the
    receiver, while another spawned agent's are there (every agent selected: a plain box has no endpoints of its
    own by default)."""
    sim, transport, env = start_in_process(monkeypatch, WORLD, Ros2Config(sigros_agents=("all",)))
    try:
        assert sim.entities.spawn([SpawnRequest(name="crate", resource=BOX, xyz=(1.0, -1.0, 0.05)),
                          SpawnRequest(name="other", resource=BOX, xyz=(-1.0, -1.0, 0.05), namespace="/ns")]) \
            == ["crate", "other"]
        assert "crate_get_obj_position" in transport.endpoints and "/ns/other_get_obj_position" in transport.endpoints
        with client_process(env, "call_deleted.py", "/crate_get_obj_position") as proc:
            end = time.monotonic() + 30.0
            while not transport._receiver.pending and time.monotonic() < end:  # the request arrives; not served
                time.sleep(0.01)
            assert transport._receiver.pending, "the request did not arrive within 30 s"
            sim.entities.delete(["crate"])
            end = time.monotonic() + 40.0
            while proc.poll() is None and time.monotonic() < end:  # serve on until the client has its answer: the
                transport.service(0.01)  # refusal may wait for the client's response reader (then tried again)
            out, err = proc.communicate(timeout=5)
        assert proc.returncode == 0, err[-3000:]
        answer = last_json(out)["answer"]
        assert answer is not None and answer["success"] is False
        assert "deleted" in answer["message"]
        assert not [name for name in transport.endpoints if "crate" in name]
        assert not [s for s, _ in transport._receiver._srvs if "crate" in s.srv_name]
        assert "/ns/other_get_obj_position" in transport.endpoints
    finally:
        transport.stop()


def test_spawned_agents_follow_the_sigros_agents_selection(monkeypatch: pytest.MonkeyPatch) -> None:
    """With sigros_agents="robots tag:keep", a spawned object gets sig_ros endpoints (published topics included)
    only when it carries the tag, and a spawned robot gets them and its joint_states; deleting the robot removes
    its joint_states."""
    env = ros_env()
    for key in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE"):
        monkeypatch.setenv(key, env[key])
    sim = Simulation(parse_world(WORLD), "bullet")
    sim.control.pause()
    transport = Ros2Transport(Ros2Config(sigros_agents=("robots", "tag:keep")))
    transport.start(sim)
    try:
        sigbot = str(WORLD.parents[3] / "worlds" / "models" / "sigbot" / "sigbot.urdf")
        assert sim.entities.spawn([SpawnRequest(name="plain", resource=BOX, xyz=(1.0, -1.0, 0.05)),
                          SpawnRequest(name="kept", resource=BOX, xyz=(-1.0, -1.0, 0.05), tags=("keep",)),
                          SpawnRequest(name="rover", uri=sigbot, xyz=(1.0, 1.0, 0.0))]) == ["plain", "kept", "rover"]
        names = set(transport.endpoints)
        assert not [n for n in names if n.startswith(("plain_", "/plain_"))]
        assert {"kept_get_obj_position", "kept_onRecvMsg", "rover_get_obj_position", "/rover/joint_states"} <= names
        sim.entities.delete(["rover"])
        assert not [n for n in transport.endpoints if "rover" in n]
    finally:
        transport.stop()


def test_a_refusal_that_cannot_be_delivered_yet_is_tried_again_before_its_service_is_destroyed(
        monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture) -> None:
    """A spawned box's service gets requests from a client whose response reader never matches (incompatible
    durability: a real rmw timeout on each send); the box is deleted while one is queued: its refusal is kept and
    tried again, the service stays alive (out of the transport's endpoints and the receiver) until the refusal is
    dropped after GIVE_UP, and is destroyed then, not before."""
    import logging

    from sigcore_ros2 import responses

    monkeypatch.setattr(responses, "GIVE_UP", 1.0)
    sim, transport, env = start_in_process(monkeypatch, WORLD, Ros2Config(sigros_agents=("all",)))
    assert transport.sigros is not None
    node = transport.sigros.node
    stack = contextlib.ExitStack()
    try:
        assert sim.entities.spawn([SpawnRequest(name="crate", resource=BOX, xyz=(1.0, -1.0, 0.05))]) == ["crate"]
        proc = stack.enter_context(client_process(env, "unmatched_call.py", "/crate_get_obj_position",
                                                  "sigcore_msgs/srv/GetObjPosition", stdin=True))
        end = time.monotonic() + 60.0
        while not transport._receiver.pending and time.monotonic() < end:  # a request arrives; not served
            time.sleep(0.01)
        assert transport._receiver.pending, "the request did not arrive within 60 s"
        with caplog.at_level(logging.WARNING, logger="sigcore.ros2"):
            sim.entities.delete(["crate"])
            alive_after_delete = any(s.srv_name.lstrip("/") == "crate_get_obj_position" for s in node.services)
            end = time.monotonic() + 30.0  # GIVE_UP (1 s) and a round are enough; a bound for a loaded machine
            while not _dropped(caplog) and time.monotonic() < end:
                transport.service(0.05)
            transport.service(0.05)
        dropped = _dropped(caplog)
        alive_at_end = any(s.srv_name.lstrip("/") == "crate_get_obj_position" for s in node.services)
        tell_stop(proc)
        out, err = proc.communicate(timeout=30)
    finally:
        stack.close()
        transport.stop()
    assert proc.returncode == 0, err[-3000:]
    assert last_json(out)["answered"] is False  # the case is real
    assert alive_after_delete  # kept alive while its refusal waits
    assert dropped and all(m.startswith("crate_get_obj_position: ") for m in dropped), dropped
    assert not alive_at_end  # destroyed once the refusal was dropped
    assert not [name for name in transport.endpoints if "crate" in name]


def _dropped(caplog: pytest.LogCaptureFixture) -> list[str]:
    """The warnings saying a response was dropped."""
    return [r.getMessage() for r in caplog.records if "a response was dropped" in r.getMessage()]
