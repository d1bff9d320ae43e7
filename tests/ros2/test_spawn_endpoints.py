"""Endpoints of agents that come and go (the transport in this process, its client in another): a spawned robot's
request still queued when the robot is deleted is answered with a refusal, and its endpoints leave the transport."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import CLIENTS, WORLD, ros_env, start_in_process  # noqa: E402
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
    proc = None
    try:
        assert sim.entities.spawn([SpawnRequest(name="crate", resource=BOX, xyz=(1.0, -1.0, 0.05)),
                          SpawnRequest(name="other", resource=BOX, xyz=(-1.0, -1.0, 0.05), namespace="/ns")]) \
            == ["crate", "other"]
        assert "crate_get_obj_position" in transport.endpoints and "/ns/other_get_obj_position" in transport.endpoints
        proc = subprocess.Popen([sys.executable, str(CLIENTS / "call_deleted.py"), "/crate_get_obj_position"],
                                env=env, text=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                start_new_session=True)
        end = time.monotonic() + 30.0
        while not transport._receiver.pending and time.monotonic() < end:  # the request arrives; not served
            time.sleep(0.01)
        assert transport._receiver.pending, "the request did not arrive within 30 s"
        sim.entities.delete(["crate"])
        for _ in range(100):  # serve on (nothing of crate's is left to serve)
            transport.service(0.01)
        out, err = proc.communicate(timeout=40)
        assert proc.returncode == 0, err[-3000:]
        answer = json.loads(out.strip().splitlines()[-1])["answer"]
        assert answer is not None and answer["success"] is False
        assert "deleted" in answer["message"]
        assert not [name for name in transport.endpoints if "crate" in name]
        assert not [s for s, _ in transport._receiver._srvs if "crate" in s.srv_name]
        assert "/ns/other_get_obj_position" in transport.endpoints
    finally:
        if proc is not None and proc.poll() is None:
            os.killpg(proc.pid, 9)
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
