"""``sigcore run --viewer`` and ``sigcore view`` as a user runs them (real processes, real viser server, no
browser): the URL is said, a taken port is refused before anything runs, ``view`` starts paused."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"


def sigcore(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", *args], capture_output=True, text=True, cwd=ROOT,
                          timeout=120)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.mark.slow
def test_run_with_the_viewer_says_its_url_and_runs() -> None:
    port = free_port()
    done = sigcore("run", str(CLEANUP), "--transport", "none", "--viewer", "--viewer-port", str(port), "--steps",
                   "300", "--fast")
    assert done.returncode == 0, done.stderr
    assert f"ready: viewer at http://127.0.0.1:{port} is up, running as fast as possible" in done.stderr
    assert "steps:    300" in done.stdout
    assert "viser" not in done.stdout  # viser's own banner is not printed: sigcore says the URL


@pytest.mark.slow
def test_a_taken_port_is_refused_before_the_run() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        done = sigcore("run", str(CLEANUP), "--transport", "none", "--viewer", "--viewer-port", str(port), "--steps",
                       "10")
    assert done.returncode == 2, done.stderr
    assert f"--viewer: port {port} on 127.0.0.1 is in use by another program" in done.stderr
    assert "--viewer-port" in done.stderr and "steps:" not in done.stdout


@pytest.mark.slow
def test_paused_needs_a_transport_or_a_viewer() -> None:
    done = sigcore("run", str(CLEANUP), "--transport", "none", "--paused")
    assert done.returncode == 2
    assert "--paused needs a transport or a viewer" in done.stderr and "--viewer" in done.stderr


def test_view_starts_paused_and_a_signal_ends_it_with_the_report() -> None:
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-m", "sigcore", "view", str(CLEANUP), "--transport", "none",
                             "--viewer-port", str(port)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    lines: list[str] = []
    assert proc.stderr is not None
    reader = threading.Thread(target=lambda: lines.extend(proc.stderr), daemon=True)  # type: ignore[arg-type]
    reader.start()
    try:
        deadline = time.monotonic() + 60
        while not any("ready:" in line for line in lines) and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        ready = next((line for line in lines if "ready:" in line), "")
        assert f"ready: viewer at http://127.0.0.1:{port} is up, paused" in ready, "".join(lines)
        with socket.create_connection(("127.0.0.1", port), timeout=5):
            pass  # the page is served
        os.killpg(proc.pid, signal.SIGTERM)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    reader.join(timeout=5)
    assert proc.returncode == 0, "".join(lines)
    assert "steps:    0" in out and "stopped:  by SIGTERM" in out
