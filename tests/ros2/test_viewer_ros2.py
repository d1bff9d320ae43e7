"""The web viewer in a real headless Chromium beside the ROS 2 transport (issue 13's "done when").

``sigcore run worlds/cleanup.xml --viewer`` runs in its own process with the ROS 2 transport; a plain rclpy process
(clients/viewer_watch.py) watches /clock and /robot_000_onRecvMsg; Chromium (selenium, Debian's chromium and
chromium-driver) opens the page like a person would. Waits are bounded polls with stated timeouts: Chromium renders
WebGL in software here and its first picture takes about 10 s (60 s allowed).
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from pages import PAGE_FPS
from rosproc import CLIENTS, SimProcess, _kill, start_sim
from sigcore_viewer.browser import Browser, missing

pytestmark = [pytest.mark.ros2, pytest.mark.browser]

CLEANUP = Path(__file__).resolve().parents[2] / "worlds" / "cleanup.xml"

if os.environ.get("SIGCORE_NO_BROWSER"):
    pytest.skip("SIGCORE_NO_BROWSER is set: the viewer's browser tests are skipped", allow_module_level=True)
if missing() is not None:  # scripts/setup.sh installs them as root: a missing browser is a failed set-up
    raise RuntimeError(f"the viewer's browser tests cannot run: {missing()}")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Watcher:
    """clients/viewer_watch.py: its newest JSON line (the /clock and the messages robot_000 received)."""

    def __init__(self, env: dict[str, str]) -> None:
        self.proc = subprocess.Popen([sys.executable, str(CLIENTS / "viewer_watch.py")], env=env,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                     start_new_session=True)
        self.last: dict = {}
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.startswith("{"):
                self.last = json.loads(line)

    def clock(self) -> float | None:
        return self.last.get("clock")

    def wait(self, predicate: object, timeout: float, what: str) -> None:
        end = time.monotonic() + timeout
        while not predicate():  # type: ignore[operator]
            assert time.monotonic() < end, f"after {timeout:g} s: {what}; the watcher saw {self.last}"
            time.sleep(0.1)


@pytest.fixture(scope="module")
def running(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[SimProcess, Watcher, str]]:
    port = _free_port()
    sim = start_sim(tmp_path_factory.mktemp("viewer"), CLEANUP, "--viewer", "--viewer-port", str(port))
    watcher = Watcher(sim.env)
    try:
        watcher.wait(lambda: watcher.clock() is not None, 60, "/clock arrives")
        yield sim, watcher, f"http://127.0.0.1:{port}"
    finally:
        _kill(watcher.proc)
        sim.stop()


def _robot_blue(image: np.ndarray) -> np.ndarray:
    """Pixels of the robot's body colour (URDF 'blue', rgb 0.2 0.35 0.75), shaded: clearly blue."""
    r, g, b = (image[:, :, k].astype(int) for k in range(3))
    return (b > 110) & (b > r + 60) & (b > g + 35)


def _wall(image: np.ndarray) -> np.ndarray:
    """Pixels of the walls' colour (0.85 0.82 0.75), shaded: light, warm grey."""
    r, g, b = (image[:, :, k].astype(int) for k in range(3))
    return (r > 120) & (r < 235) & (r - b > 8) & (r - b < 45) & (abs(r - g) < 16)


def test_page_shows_the_room_and_the_robot_and_steers_the_run(running: tuple[SimProcess, Watcher, str]) -> None:
    sim, watcher, url = running
    with Browser(url, max_fps=PAGE_FPS) as page:
        page.wait(lambda p: "cleanup" in p.text() and "score: 0" in p.text(), 60, "the panel shows the world, score")

        # the picture: the room (walls all across the scene) and the robot where it stands (x = -4, the room's
        # west end: the left part of the scene, which spans the page left of the panel)
        def drawn(p: Browser) -> np.ndarray | None:
            p.dismiss_notifications()
            image = p.screenshot()
            return image if _robot_blue(image[:, :900]).sum() > 150 else None
        image = page.wait(drawn, 60, "the robot's blue appears in the picture")
        scene = image[:, :900]
        ys, xs = np.nonzero(_robot_blue(scene))
        wall_ys, wall_xs = np.nonzero(_wall(scene))
        assert len(wall_xs) > 5000, f"only {len(wall_xs)} wall-coloured pixels: the room is not drawn"
        left, right = np.percentile(wall_xs, [2, 98])
        assert right - left > 500, f"the walls span x {left:.0f}..{right:.0f} px only"
        x_robot = (float(np.median(xs)) - left) / (right - left)
        assert 0.0 < x_robot < 0.3, f"the robot is drawn at {x_robot:.2f} of the room's width; expected its west end"
        assert np.percentile(wall_ys, 2) < np.median(ys) < np.percentile(wall_ys, 98), "the robot is not in the room"

        # a person's message to robot_000 reaches a separate rclpy process on /robot_000_onRecvMsg
        page.pick("To", "robot_000")
        page.type("Message", "please bring me the can")
        page.click("Send")
        watcher.wait(lambda: {"sender": "viewer", "content": "please bring me the can"} in
                     watcher.last.get("received", []), 20, "robot_000_onRecvMsg delivers the viewer's message")
        page.wait(lambda p: "sent to robot_000" in p.text(), 10, "the page confirms the message")

        # pause in the page: /clock stops (it was running: real time)
        t0 = watcher.clock()
        watcher.wait(lambda: (watcher.clock() or 0) > (t0 or 0) + 0.3, 10, "/clock advances while running")
        page.click("Pause")
        page.wait(lambda p: "paused" in p.text(), 10, "the page says paused")
        time.sleep(0.5)  # /clock messages already on their way arrive
        still = watcher.clock()
        time.sleep(2.0)
        assert watcher.clock() == pytest.approx(still, abs=1e-9), "/clock went on after Pause"

        # a second browser sees the same run; the first one closing abruptly changes nothing
        with Browser(url, max_fps=PAGE_FPS) as second:
            second.wait(lambda p: "paused" in p.text(), 60, "the second page shows the same paused run")
            page.close()
            second.click("Play")
            watcher.wait(lambda: (watcher.clock() or 0) > (still or 0) + 0.5, 20, "/clock resumes after Play")
            second.wait(lambda p: "running" in p.text(), 10, "the second page shows it running")
    assert sim.alive(), sim.output()[-2000:]
