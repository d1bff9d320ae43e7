"""``sigcore run --viewer`` after the run (``--viewer-linger``, ``sigcore/cli/linger.py``), without a browser: a run
without a terminal ends at once, ``--viewer-linger S`` keeps the process (and the page) up S seconds, Enter in a
terminal ends the wait, a signal ends it, and the exit code is still the task's verdict. Real processes, a real
viewer process and viser server; the terminal is a real pseudo-terminal (``pty``)."""

from __future__ import annotations

import os
import pty
import re
import select
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
SIGCORE = [sys.executable, "-m", "sigcore"]
WAITING = "viewer: the run has ended"
"""The line ``sigcore run`` says when the page stays up after the run."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def short_run(*extra: str) -> list[str]:
    """A bare run of 50 steps with the viewer on a free port."""
    return [*SIGCORE, "run", str(CLEANUP), "--transport", "none", "--viewer", "--viewer-port", str(free_port()),
            "--steps", "50", "--fast", "-q", *extra]


@pytest.mark.slow
def test_without_a_terminal_the_run_ends_at_once() -> None:
    """Without a terminal (output piped, as under eval or CI) and no --viewer-linger, nothing waits after the run."""
    t0 = time.monotonic()
    done = subprocess.run(short_run(), capture_output=True, text=True, cwd=ROOT, timeout=120,
                          stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr
    assert "steps:    50" in done.stdout and WAITING not in done.stderr
    assert time.monotonic() - t0 < 60, "the run took a minute: something waited after it"


@pytest.mark.slow
def test_linger_keeps_the_process_up_that_long_then_it_exits_with_the_verdict() -> None:
    """--viewer-linger 4 without a browser: the process exits 0 after the run plus 4 s (not before, and not long
    after: wide margins for a loaded machine)."""
    proc = subprocess.Popen(short_run("--viewer-linger", "4"), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=ROOT, stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        assert proc.stderr is not None
        lines = []
        for line in proc.stderr:  # up to the line said when the wait starts
            lines.append(line)
            if WAITING in line:
                break
        said = time.monotonic()
        assert any(WAITING in line for line in lines), "".join(lines)
        assert "(at most 4 s)" in lines[-1] and "press Enter" not in lines[-1], lines[-1]
        out, _ = proc.communicate(timeout=60)
        waited = time.monotonic() - said
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 0
    assert "steps:    50" in out  # the results were printed before the wait
    assert 3.0 < waited < 30.0, f"the process waited {waited:.1f} s after the run; --viewer-linger 4"


@pytest.mark.slow
def test_a_failed_task_still_exits_1_after_lingering(tmp_path: Path) -> None:
    """The referee's time limit (3 s) ends the task as failed: after the wait the exit code is 1, as without a
    viewer."""
    world = tmp_path / "cleanup_short.xml"
    text = CLEANUP.read_text()
    assert 'time_limit="600"' in text
    world.write_text(text.replace('time_limit="600"', 'time_limit="3"'))
    (tmp_path / "models").symlink_to(CLEANUP.parent / "models")  # its URDFs, relative to the world file
    done = subprocess.run([*SIGCORE, "run", str(world), "--transport", "none", "--viewer", "--viewer-port",
                           str(free_port()), "--fast", "-q", "--duration", "60", "--viewer-linger", "1"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120, stdin=subprocess.DEVNULL)
    assert "time_limit" in done.stdout and WAITING in done.stderr, done.stdout + done.stderr
    assert done.returncode == 1, done.stdout + done.stderr


def _read_until(fd: int, needle: str, timeout: float) -> str:
    """What the pseudo-terminal ``fd`` printed, up to ``needle`` (AssertionError after ``timeout`` s)."""
    seen = ""
    end = time.monotonic() + timeout
    while needle not in seen:
        left = end - time.monotonic()
        assert left > 0, f"after {timeout:g} s the terminal shows no {needle!r}:\n{seen[-2000:]}"
        ready, _, _ = select.select([fd], [], [], min(left, 0.5))
        if ready:
            try:
                seen += os.read(fd, 65536).decode(errors="replace")
            except OSError:  # the process ended: nothing more to read
                break
    return seen


def _start_in_terminal(*extra: str) -> tuple[subprocess.Popen[bytes], int]:
    """``sigcore run`` with a pseudo-terminal as its standard input and error (a person at a terminal)."""
    main, other = pty.openpty()
    proc = subprocess.Popen(short_run(*extra), stdin=other, stdout=subprocess.DEVNULL, stderr=other, cwd=ROOT,
                            start_new_session=True)
    os.close(other)
    return proc, main


@pytest.mark.slow
def test_enter_in_the_terminal_ends_the_wait() -> None:
    """With a terminal the page stays without a time limit, until Enter: then the process exits 0 at once."""
    proc, terminal = _start_in_terminal()
    try:
        said = _read_until(terminal, "to exit", 90)
        assert "press Enter here" in said and "at most" not in said, said[-500:]
        time.sleep(2.0)
        assert proc.poll() is None, "the process did not wait for Enter"
        os.write(terminal, b"\n")
        t0 = time.monotonic()
        code = proc.wait(timeout=30)
        assert time.monotonic() - t0 < 15, "Enter took more than 15 s to end the wait"
        assert code == 0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(terminal)


@pytest.mark.slow
def test_a_signal_ends_the_wait_with_the_verdict() -> None:
    """SIGTERM while the page lingers ends the process with the task's exit code (0), not as an abort."""
    proc, terminal = _start_in_terminal("--viewer-linger", "600")
    try:
        said = _read_until(terminal, "to exit", 90)
        assert "(at most 600 s)" in said and re.search(r"press Enter here", said), said[-500:]
        os.killpg(proc.pid, signal.SIGTERM)
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(terminal)


@pytest.mark.slow
def test_linger_0_never_waits_even_with_a_terminal() -> None:
    """--viewer-linger 0 with a terminal: the run ends as without a viewer, nothing is said about waiting."""
    proc, terminal = _start_in_terminal("--viewer-linger", "0")
    try:
        seen = _read_until(terminal, "\x00 never printed \x00", 90)  # everything, until the terminal closes
        assert proc.wait(timeout=30) == 0, seen[-2000:]
        assert "ready: viewer at" in seen and WAITING not in seen, seen[-2000:]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(terminal)
