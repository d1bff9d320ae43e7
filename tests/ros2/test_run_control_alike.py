"""One run-state machine (issue 29, item 3): play, pause, step 10, reset and play, once through the web viewer's
commands and once through simulation_interfaces, pass the run control through the same states at the same step
counts.

Both runs are driven in lockstep from the test thread, which plays the simulation thread as ``sigcore.sim.run``
does: it services the client's side (the viewer, or the ROS 2 transport with a client in another process) until the
next verb arrives (a ``control`` event), then takes a fixed number of loop passes without servicing anything, so the
step counts do not depend on timing. The next verb is sent only after those passes (the viewer's next button press;
the ROS 2 client waits for "go" on its standard input), so two verbs never arrive in one servicing."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import astuple

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import CLIENTS, WORLD, start_in_process  # noqa: E402

from sigcore.sim import ControlChange, Simulation  # noqa: E402
from sigcore.world import parse_world  # noqa: E402

pytestmark = [pytest.mark.ros2, pytest.mark.slow]

PASSES = {"play": 5, "pause": 3, "step": 12, "reset": 3}
"""Loop passes taken after each verb: 5 free steps after play, none after pause, 10 pending steps and 2 idle
passes after step 10, none after reset (paused)."""

EXPECTED = [  # (verb, paused, pending steps, step count when done; step count after the passes)
    (("play", False, 0, 0), 5),
    (("pause", True, 0, 5), 5),
    (("step", True, 10, 5), 15),
    (("reset", True, 0, 15), 15),  # time goes on: a reset does not move the step count back
    (("play", False, 0, 15), 20),
]
TIMEOUT = 30.0
"""Wall seconds a verb may take to arrive (milliseconds here; generous for a loaded CI)."""


def drive(sim: Simulation, service: Callable[[], None], verbs: int,
          passed: Callable[[], None] = lambda: None) -> list[tuple[tuple[object, ...], int]]:
    """Service until each of ``verbs`` verbs arrives, then take its passes and call ``passed`` (the client may send
    the next verb): the verbs seen, with the step count after their passes."""
    changes: list[ControlChange] = []
    sim.events.subscribe("control", changes.append)
    seen: list[tuple[tuple[object, ...], int]] = []
    while len(seen) < verbs:
        deadline = time.monotonic() + TIMEOUT
        while len(changes) <= len(seen):
            assert time.monotonic() < deadline, f"verb {len(seen) + 1} did not arrive within {TIMEOUT} s"
            service()
        change = changes[len(seen)]
        for _ in range(PASSES[change.verb]):
            if sim.control.take_step():
                sim.step()
        state = astuple(change)
        seen.append(((state[0], state[1], state[2], state[5]), sim.step_count))
        if len(seen) < verbs:
            passed()
    assert len(changes) == verbs  # nothing else changed the run state
    return seen


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_viewer_and_simulation_interfaces_drive_the_run_control_alike(monkeypatch: pytest.MonkeyPatch) -> None:
    """The same five verbs give the same states and step counts from the viewer's buttons and from
    set_simulation_state / step_simulation / reset_simulation; every ROS 2 request is answered OK."""
    from sigcore_viewer.commands import pause, play, reset, step
    from sigcore_viewer.viewer import WebViewer

    sim = Simulation(parse_world(WORLD), "mujoco")
    sim.control.pause()
    viewer = WebViewer(port=free_port())
    try:
        viewer.open()
        viewer.start(sim)
        commands = iter([play, pause, step(10), reset, play])
        pending: list[bool] = [True]

        def service_viewer() -> None:  # one command per verb, as a person presses one button at a time
            if pending[0]:
                viewer._post(next(commands))
                pending[0] = False
            viewer.service(0.0)
            time.sleep(0.001)

        def next_command(change: ControlChange) -> None:
            pending[0] = True

        sim.events.subscribe("control", next_command)
        by_viewer = drive(sim, service_viewer, len(EXPECTED))
    finally:
        viewer.stop()

    sim, transport, env = start_in_process(monkeypatch, WORLD)
    proc = subprocess.Popen([sys.executable, str(CLIENTS / "run_control.py")], env=env, text=True,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)

    def go() -> None:
        assert proc.stdin is not None
        proc.stdin.write("go\n")
        proc.stdin.flush()

    try:
        by_ros = drive(sim, lambda: transport.service(0.01), len(EXPECTED), go)
        deadline = time.monotonic() + TIMEOUT
        while proc.poll() is None and time.monotonic() < deadline:
            transport.service(0.01)  # the last answer goes out
        out, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, 9)
        transport.stop()
    assert proc.returncode == 0, err[-3000:]
    assert json.loads(out.strip().splitlines()[-1]) == {"results": [1, 1, 1, 1, 1]}  # RESULT_OK each
    assert by_viewer == EXPECTED
    assert by_ros == by_viewer
