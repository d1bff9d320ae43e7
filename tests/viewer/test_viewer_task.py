"""The web viewer watching the clean-up task, in a real headless Chromium (``sigcore_viewer.browser``: selenium
with Debian's chromium and chromium-driver): the README's command (``examples/cleanup/run_task.py --viewer``: the
task solved over ROS 2, nodes in processes of their own) shows a score above 0 after 30 s of the task, and after the
run the page keeps the final moment, the result and the score table until the page is closed.

Chromium renders WebGL in software here, sharing 2 CPUs with the run: the tests wait with bounded polls and wide,
stated margins, and read the page's text (the panel's DOM), not its pixels, for the figures.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from pages import PAGE_FPS
from rosdomains import next_domain
from sigcore_viewer.browser import Browser, missing

pytestmark = [pytest.mark.ros2, pytest.mark.browser, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
RUN_TASK = ROOT / "examples" / "cleanup" / "run_task.py"
URL = re.compile(r"viewer at (http://127\.0\.0\.1:\d+)")


@pytest.fixture(autouse=True)
def browser_ready() -> None:
    if os.environ.get("SIGCORE_NO_BROWSER"):
        pytest.skip("SIGCORE_NO_BROWSER is set: the viewer's browser tests are skipped")
    if missing() is not None:  # scripts/setup.sh installs them as root: a missing browser is a failed set-up
        raise RuntimeError(f"the viewer's browser tests cannot run: {missing()}")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Command:
    """A command in a process group of its own, its output in ``log``, without a terminal."""

    def __init__(self, args: list[str], log: Path, preexec: Callable[[], None] | None = None) -> None:
        self.log = log
        self._out = log.open("w")
        self.proc = subprocess.Popen(args, cwd=ROOT, stdin=subprocess.DEVNULL, stdout=self._out,
                                     stderr=subprocess.STDOUT, start_new_session=True, preexec_fn=preexec,
                                     env={**os.environ, "PYTHONUNBUFFERED": "1"})

    def output(self) -> str:
        self._out.flush()
        return self.log.read_text()

    def url(self, timeout: float) -> str:
        """The viewer's URL, once the command said it is ready."""
        end = time.monotonic() + timeout
        while True:
            found = URL.search(self.output())
            if found:
                return found.group(1)
            assert self.proc.poll() is None, f"the command ended ({self.proc.returncode}):\n{self.output()[-3000:]}"
            assert time.monotonic() < end, f"no viewer URL after {timeout:g} s:\n{self.output()[-3000:]}"
            time.sleep(0.2)

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self._out.close()


def page_time(page: Browser) -> float | None:
    """The simulated time the page's run line shows [s]."""
    found = re.search(r"t = (\d+\.\d+) s", page.text())
    return float(found.group(1)) if found else None


def page_score(text: str) -> int | None:
    """The score the page's Task panel shows."""
    found = re.search(r"score: (-?\d+)", text)
    return int(found.group(1)) if found else None


def test_the_readme_command_shows_the_task_being_solved_and_the_end_stays(tmp_path: Path) -> None:
    """``run_task.py --viewer`` (the README's "Watching it"), at 3x real time (a person watches at 1x, the
    default; pacing has tests of its own): after 30 s of simulated task time the page shows a score above 0 (the
    first grasp scores at about 12 s); at the end it shows "ended", the result and the score table and keeps them
    (5 s later still); closing the page then ends the process with the task's exit code 0."""
    port = free_port()
    task = Command([sys.executable, str(RUN_TASK), "--domain", str(next_domain()), "--viewer", "--viewer-port",
                    str(port), "--viewer-linger", "900", "--factor", "3"],
                   tmp_path / "run_task.log")
    try:
        url = task.url(120)
        assert url == f"http://127.0.0.1:{port}"
        page = Browser(url, max_fps=PAGE_FPS)
        try:
            page.wait(lambda p: (page_time(p) or 0.0) >= 30.0, 240, "30 s of the task in the page")
            page.dismiss_notifications()
            shot = tmp_path / "task_30s.png"
            page.save(shot)
            image = page.screenshot()
            assert shot.stat().st_size > 10_000 and float(np.std(image)) > 10, "a blank screenshot"
            text = page.text()
            score = page_score(text)
            assert score is not None and score > 0, f"score {score} after 30 s of the task; the page says:\n{text}"

            ended = page.wait(lambda p: "ended" in p.text() and "succeeded: score" in p.text() and p.text(), 600,
                              "the end of the task in the page (run_task's own timeout: 600 s with --viewer)")
            assert "referee (cleanup rules): succeeded at t =" in ended  # the score table, its first line
            assert re.search(r"correct_box\s+\+1000", ended), ended
            final = page_time(page)
            time.sleep(5.0)
            later = page.text()
            assert "succeeded: score" in later and "referee (cleanup rules)" in later and page_time(page) == final
            assert task.proc.poll() is None, "the process ended while the page was open (--viewer-linger 900)"
            summary = re.search(r"simulated: ([\d.]+) s", task.output())
            assert summary is not None, task.output()[-3000:]
        finally:
            page.close()
        code = task.proc.wait(timeout=60)  # the page closed: the wait ends
        assert code == 0, task.output()[-3000:]
        assert "simulator exited 0" in task.output()
    finally:
        task.stop()


def test_after_the_run_the_page_keeps_the_last_moment_until_it_is_closed(tmp_path: Path) -> None:
    """A run without ROS (the scripted robot at 10x real time): the page opened once it is ready shows, after the
    referee ends the task, the state "ended", the final simulated time the run printed, the result and the score
    table, with the run's controls disabled; the process waits (--viewer-linger 300) until the page is closed, then
    exits 0 within 30 s."""
    command = Command([sys.executable, "-m", "sigcore", "run", str(CLEANUP), "--transport", "none", "--controller",
                       "robot_000=cleanup.robot", "--viewer", "--viewer-port", str(free_port()), "--factor", "10",
                       "-q", "--viewer-linger", "300"], tmp_path / "run.log")
    try:
        page = Browser(command.url(120), max_fps=PAGE_FPS)
        try:
            text = page.wait(lambda p: "ended" in p.text() and "succeeded: score" in p.text() and p.text(), 240,
                             "the end of the task in the page")
            assert "the run has ended" in text and "referee (cleanup rules): succeeded at t =" in text, text
            printed = re.search(r"simulated: ([\d.]+) s", command.output())
            assert printed is not None, command.output()
            shown = page_time(page)
            assert shown is not None and abs(shown - float(printed.group(1))) < 0.011, (shown, printed.group(1))
            play = page.driver.find_element("xpath", "//button[normalize-space()='Play']")
            assert not play.is_enabled(), "the run's Play button is still enabled after the run"
            assert command.proc.poll() is None, "the process ended while the page was open"
            assert "Traceback" not in command.output(), command.output()[-3000:]
            closed_at = None
        finally:
            page.close()
            closed_at = time.monotonic()
        code = command.proc.wait(timeout=60)
        assert code == 0, command.output()[-3000:]
        assert time.monotonic() - closed_at < 30, "the process went on long after the page was closed"
    finally:
        command.stop()


def _block_sigint() -> None:
    """In the child before exec: SIGINT blocked and ignored, as a parent may leave it (a thread that blocked it, a
    shell's background job)."""
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.parametrize("started", ["default", "sigint-blocked"])
def test_ctrl_c_in_the_terminal_ends_the_task_and_its_processes(tmp_path: Path, started: str) -> None:
    """Ctrl-C on ``run_task.py --viewer`` (the signal reaches run_task's process group only: the simulator and the
    two nodes run in sessions of their own) is passed on: the simulator ends its run and prints its results, run_task
    exits with the simulator's code and no traceback, and nothing is left behind (the viewer's port is free again).
    The same when run_task was started with SIGINT blocked and ignored (it takes Ctrl-C back)."""
    port, domain = free_port(), next_domain()
    task = Command([sys.executable, str(RUN_TASK), "--domain", str(domain), "--viewer", "--viewer-port",
                    str(port), "--viewer-linger", "900"],
                   tmp_path / "run_task.log", _block_sigint if started == "sigint-blocked" else None)
    try:
        task.url(120)
        end = time.monotonic() + 120
        while "every awaited topic has its peers" not in task.output():  # the nodes found it: the task runs
            assert time.monotonic() < end and task.proc.poll() is None, task.output()[-3000:]
            time.sleep(0.2)
        time.sleep(2.0)
        os.killpg(task.proc.pid, signal.SIGINT)
        code = task.proc.wait(timeout=60)
        out = task.output()
        assert "Traceback" not in out and "KeyboardInterrupt" not in out, out[-3000:]
        assert "run_task: interrupted; stopping the simulator" in out
        assert re.search(r"simulated: [\d.]+ s", out), out[-3000:]  # the simulator printed its results
        assert f"run_task: simulator exited {code};" in out
        end = time.monotonic() + 30
        while not _port_free(port):
            assert time.monotonic() < end, f"port {port} still taken 30 s after run_task ended"
            time.sleep(0.5)
    finally:
        task.stop()
        _kill_strays(domain)


def _kill_strays(domain: int) -> None:
    """Kill the process group of every process that runs in ROS 2 domain ``domain`` (the simulator and the nodes
    that run_task started in sessions of their own and did not stop, when the test failed): none lingers on after
    the test. The domain is this test's alone (``next_domain``)."""
    mine = os.getpgid(0)
    wanted = f"ROS_DOMAIN_ID={domain}".encode()
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            if wanted in (proc / "environ").read_bytes().split(b"\0") and os.getpgid(int(proc.name)) != mine:
                os.killpg(os.getpgid(int(proc.name)), signal.SIGKILL)
        except (OSError, ProcessLookupError):
            continue


def _port_free(port: int) -> bool:
    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
        return True
