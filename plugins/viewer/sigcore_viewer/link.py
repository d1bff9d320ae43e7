"""The web viewer's link to its process (the viewer's process, :mod:`sigcore_viewer.front`, runs viser's server):
:class:`FrontLink` starts it on a free port and waits for it to listen, talks to it over a Unix socket that never
blocks the simulation (messages queued for the socket, requests and reports read as they arrive), takes its reports
(snapshots handed to viser, browsers connected, where a scene node is) and ends it.
"""

from __future__ import annotations

import collections
import logging
import select
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

from sigcore.errors import ViewerError
from sigcore.viewer import DEFAULT_PORT, Viewer

from .exceptions import PeerGone
from .overlays import OVERLAYS
from .snapshot import Pushed
from .wire import Inbox, Outbox, receive, tune

log = logging.getLogger("sigcore.viewer")


class FrontLink(Viewer):
    """The viewer's process and the socket to it, for :class:`~sigcore_viewer.viewer.WebViewer` (which serves the
    simulation or a recording through it). See :class:`sigcore.viewer.Viewer` for the arguments."""

    READY_TIMEOUT = 60.0
    """Wall seconds the viewer's process may take to import viser and listen (about 1 s; generous for a loaded
    machine)."""

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, rate: float = 30.0) -> None:
        super().__init__(host, port, rate)
        self._proc: subprocess.Popen[bytes] | None = None
        self._sock: socket.socket | None = None
        self._outbox: Outbox | None = None
        self._inbox: Inbox | None = None
        self._listening: int | None = None
        self._overlays = dict(OVERLAYS)  # the overlay switches (the viewer's process starts with them)
        self._probed: dict[str, Any] = {}
        self._probe_cond = threading.Condition()
        self._probe_requests: collections.deque[str] = collections.deque()  # node_pose from another thread
        self._player_thread: threading.Thread | None = None  # the thread playing a recording back
        self._clients = 0  # browsers connected now (as the viewer's process reports)
        self.pushed = 0
        """Snapshots the viewer's process has handed to viser, which sends them to the browsers (as reported)."""
        self.push_observers: list[Callable[[Pushed], None]] = []
        """Called on the simulation thread (in :meth:`service`) with each report of a snapshot handed to viser
        (the bench measures the latency with it)."""

    # ------------------------------------------------------------------ the viewer's process
    @property
    def url(self) -> str:
        if self._listening is None:
            raise ViewerError("the viewer is not open yet (open() or start())")
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self._listening}"

    @property
    def process_id(self) -> int | None:
        """The viewer's process (viser's server), or None when it is not running."""
        return self._proc.pid if self._proc is not None and self._proc.poll() is None else None

    def open(self) -> None:
        """Start the viewer's process, listening on the port (the next free one from 8080 when none was given);
        :attr:`url` is known after.

        Raises:
            ViewerError: the port given is taken, no port from 8080 to 8179 is free, or the viewer's process could
                not start (the message says why).
        """
        if self._proc is not None:
            return
        if self.port is not None:
            if not _free(self.host, self.port):
                raise ViewerError(f"port {self.port} on {self.host} is in use by another program; choose another "
                                  f"--viewer-port, or leave it out to take the next free port from {DEFAULT_PORT}")
            port = self.port
        else:
            found = next((p for p in range(DEFAULT_PORT, DEFAULT_PORT + 100) if _free(self.host, p)), None)
            if found is None:
                raise ViewerError(f"no free port from {DEFAULT_PORT} to {DEFAULT_PORT + 99} on {self.host}; "
                                  "give one with --viewer-port")
            port = found
            if port != DEFAULT_PORT:
                log.warning("viewer: port %d is in use; the viewer listens on port %d", DEFAULT_PORT, port)
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        tune(ours)
        tune(theirs)
        command = [sys.executable, "-m", "sigcore_viewer.front", "--fd", str(theirs.fileno()), "--host", self.host,
                   "--port", str(port), *(f"--overlay={k}={int(v)}" for k, v in self._overlays.items())]
        try:
            # viser prints its failures (a callback's, a connection's) on stdout: they join the run's stderr
            proc = subprocess.Popen(command, pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                                    stdout=_stderr())
        except OSError as e:
            ours.close()
            raise ViewerError(f"the viewer's process could not start: {e}") from None
        finally:
            theirs.close()
        ours.settimeout(self.READY_TIMEOUT)
        try:
            answer = receive(ours)
        except (PeerGone, TimeoutError, ValueError) as e:
            end_process(proc)
            ours.close()
            raise ViewerError(f"the viewer's process ended or did not answer within {self.READY_TIMEOUT:g} s "
                              f"(exit code {proc.returncode}; its error is printed above): {e}") from None
        if answer[0] != "ready":
            end_process(proc)
            ours.close()
            raise ViewerError(f"the viewer could not listen on {self.host}:{port}: {answer[1]}")
        self._listening = int(answer[1])
        if self._listening != port:
            log.warning("viewer: port %d was taken meanwhile; the viewer listens on port %d", port,
                        self._listening)
        ours.setblocking(False)
        self._proc, self._sock, self._outbox, self._inbox = proc, ours, Outbox(ours), Inbox(ours)

    @property
    def clients(self) -> int:
        """The browsers connected now, as the viewer's process last reported."""
        return self._clients

    def close(self) -> None:
        if self._outbox is not None and self._sock is not None:
            try:
                self._outbox.put(("stop",))
                deadline = time.monotonic() + 2.0
                while not self._outbox.flush() and time.monotonic() < deadline:
                    select.select([], [self._sock], [], 0.1)
            except PeerGone:
                pass
        if self._sock is not None:
            self._sock.close()
        if self._proc is not None:
            end_process(self._proc)
        self._proc, self._sock, self._outbox, self._inbox, self._listening = None, None, None, None, None

    def _report(self, message: tuple[Any, ...]) -> bool:
        """Take a report of the viewer's process (a snapshot pushed to the browsers, a probed node's pose); False
        when ``message`` is a person's request instead."""
        kind = message[0]
        if kind == "pushed":
            self.pushed += 1
            report = Pushed(*message[1:])
            for observer in list(self.push_observers):
                observer(report)
            return True
        if kind == "clients":
            self._clients = int(message[1])
            return True
        if kind == "probed":
            with self._probe_cond:
                self._probed[message[1]] = message[2]
                self._probe_cond.notify_all()
            return True
        return False

    def _flush(self) -> bool:
        """Send what waits for the socket; whether the viewer's process is there and everything was sent."""
        if self._outbox is None:
            return False
        try:
            return self._outbox.flush()
        except PeerGone as e:
            self._lost(e)
            return False

    def _send(self, message: tuple[Any, ...]) -> None:
        if self._outbox is None:
            return
        try:
            self._outbox.put(message)
        except PeerGone as e:
            self._lost(e)

    def _lost(self, error: Exception) -> None:
        """The viewer's process ended (or sent what is no message): go on without it."""
        code = self._proc.poll() if self._proc is not None else None
        log.warning("viewer: its process ended (exit code %s: %s); the simulation goes on without the viewer",
                    code, error)
        if self._sock is not None:
            self._sock.close()
        if self._proc is not None:
            end_process(self._proc)
        self._sock, self._outbox, self._inbox = None, None, None

    def node_pose(self, name: str, timeout: float = 10.0) -> tuple[list[float], list[float]] | None:
        """What viser in the viewer's process holds for scene node ``name`` (position, quaternion w x y z,
        relative to its parent node): what the browsers are sent. None when there is no such node. Serves the
        viewer while it waits (call it from the simulation thread; for tests and benches).

        While a recording plays back (:meth:`play_recording`), call it from any other thread: the playback asks.

        Raises:
            ViewerError: the viewer's process did not answer within ``timeout`` seconds.
        """
        player = self._player_thread
        if player is not None and player is not threading.current_thread():
            deadline = time.monotonic() + timeout
            with self._probe_cond:
                self._probed.pop(name, None)
                self._probe_requests.append(name)
                while name not in self._probed:
                    left = deadline - time.monotonic()
                    if left <= 0 or self._sock is None:
                        raise ViewerError(f"the viewer's process did not say where node {name!r} is within "
                                          f"{timeout:g} s")
                    self._probe_cond.wait(min(left, 0.1))
                answer: tuple[list[float], list[float]] | None = self._probed.pop(name)
                return answer
        self._probed.pop(name, None)
        self._send(("probe", name))
        deadline = time.monotonic() + timeout
        while name not in self._probed:
            if self._sock is None or time.monotonic() > deadline:
                raise ViewerError(f"the viewer's process did not say where node {name!r} is within {timeout:g} s")
            self.service(0.01)
        pose: tuple[list[float], list[float]] | None = self._probed.pop(name)
        return pose


def _stderr() -> int:
    """This process's stderr as a file descriptor for a child's stdout (nowhere when stderr is no file, e.g. under
    a test's capture: the run's stdout is for its results)."""
    try:
        return sys.stderr.fileno()
    except (AttributeError, OSError, ValueError):
        return subprocess.DEVNULL


def end_process(proc: subprocess.Popen[bytes]) -> None:
    """Wait for the viewer's process to end (it ends when told, or when its socket closes); stop it if it hangs."""
    try:
        proc.wait(timeout=5.0)
    except subprocess.TimeoutExpired:
        proc.terminate()
        try:
            proc.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _free(host: str, port: int) -> bool:
    """Whether ``port`` can be bound on ``host`` now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((host if host not in ("", "localhost") else "127.0.0.1", port))
        except OSError:
            return False
    return True
