"""cmd_vel times out: a client that crashes while driving does not leave its robot driving (separate processes)."""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import CLIENTS, WORLD, _kill, start_sim  # noqa: E402

pytestmark = pytest.mark.ros2

TIMEOUT = 0.3
"""The robot's ``cmd_vel_timeout`` in the test world [s] (not the default 0.5, to show the attribute is read)."""


def _world(tmp: Path) -> Path:
    """tests/data/sim/world.xml with ``cmd_vel_timeout`` on bot's <drive>."""
    text = WORLD.read_text().replace('separation="0.36"', f'separation="0.36" cmd_vel_timeout="{TIMEOUT}"')
    text = text.replace('urdf="minibot.urdf"', f'urdf="{WORLD.parent / "minibot.urdf"}"')
    assert "cmd_vel_timeout" in text
    path = tmp / "world.xml"
    path.write_text(text)
    return path


def _client(env: dict[str, str], script: str, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, str(CLIENTS / script), *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _wait_line(proc: subprocess.Popen[str], text: str, timeout: float) -> None:
    """Read ``proc``'s output until a line equal to ``text`` (bounded by ``timeout`` [s])."""
    assert proc.stdout is not None
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        ready, _, _ = select.select([proc.stdout], [], [], 0.2)
        if ready:
            line = proc.stdout.readline()
            if line.strip() == text:
                return
            if not line and proc.poll() is not None:
                break
    raise AssertionError(f"no '{text}' from {proc.args} within {timeout} s; stderr:\n"
                         f"{proc.stderr.read()[-3000:] if proc.poll() is not None and proc.stderr else ''}")


def test_wheels_stop_after_the_timeout_when_the_client_is_killed(tmp_path: Path) -> None:
    """A client publishes cmd_vel a few times and is killed (SIGKILL); the wheels stop cmd_vel_timeout (0.3 s) of
    simulated time after its last message, within -0.05/+0.1 s (joint_states every 0.02 s, wheel spin-up and
    braking take a few steps), and stay stopped."""
    sim = start_sim(tmp_path, _world(tmp_path), "--realtime")
    watch = crasher = None
    try:
        watch = _client(sim.env, "wheel_watch.py", "8.0")
        _wait_line(watch, "listening", 60.0)
        crasher = _client(sim.env, "cmd_vel_then_hang.py")
        _wait_line(crasher, "sent", 60.0)
        os.killpg(crasher.pid, signal.SIGKILL)
        out, err = watch.communicate(timeout=60.0)
        assert watch.returncode == 0, err[-3000:]
        samples = json.loads([line for line in out.splitlines() if line.startswith("{")][-1])["samples"]
        assert sim.alive()
    finally:
        for proc in (crasher, watch):
            if proc is not None:
                _kill(proc)
        sim.stop()
    driving = [t for t, v in samples if 1.5 < v < 2.5]  # 0.2 m/s on wheels of radius 0.1 m: 2 rad/s
    assert len(driving) >= 5, samples
    t_last = next(t for t, v in samples if v > 3.0)  # the last message, 0.4 m/s: 4 rad/s
    t_stop = next(t for t, v in samples if t > t_last and abs(v) < 0.2)
    assert TIMEOUT - 0.05 <= t_stop - t_last <= TIMEOUT + 0.1, (t_last, t_stop)
    after = [v for t, v in samples if t >= t_stop + 0.1]
    assert len(after) > 20 and max(abs(v) for v in after) < 0.2
