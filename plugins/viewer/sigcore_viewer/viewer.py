"""The web viewer: a :class:`sigcore.viewer.Viewer` serving the world live to any browser through viser.

Two processes, so that the browser's side never takes the simulation's interpreter (its GIL):

* in the **simulation's process**, :class:`WebViewer` is serviced between steps. It runs the person's requests
  (which arrive from the viewer's process) and, at most ``rate`` times a second of wall time, takes a
  :class:`Snapshot` - every frame's pose read from the backend, the run's state, the texts to show - and writes it
  to a Unix socket without ever blocking (a snapshot the socket has no room for is not taken; the next one is).
  Nothing else of the viewer touches the simulation;
* the **viewer's process** (:mod:`sigcore_viewer.front`, started by :meth:`WebViewer.open`) runs viser's server, the
  scene and the panel: it turns the newest snapshot into viser updates (only what changed is sent; one it had no
  time for is replaced by the next, so a slow browser never slows the simulation) and sends the person's controls
  back as plain requests. It ends with the simulation's process.

A recording (``sigcore view DIR``, :meth:`WebViewer.play_recording`) is shown the same way: the playback
(:mod:`sigcore_viewer.playback`: its clock and the moment's snapshot, from the recorded ground truth and publications)
takes the simulation's place in this process, and the viewer's process shows its snapshots with a timeline.
"""

from __future__ import annotations

import collections
import logging
import math
import select
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from time import perf_counter
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.agent.exceptions import ApiError
from sigcore.agent.robot import RobotObj
from sigcore.api.call import call
from sigcore.errors import ViewerError
from sigcore.geometry import quat_to_matrix, quat_yaw
from sigcore.publish import Publication, PublicationSink
from sigcore.sim.exceptions import RunStateError
from sigcore.text import clip, quote
from sigcore.viewer import DEFAULT_PORT, VIEWER_SENDER, Viewer
from sigcore.world.models import Object

from .exceptions import PeerGone
from .scenebuild import SceneLayout, layout_of
from .wire import Inbox, Outbox, receive, tune

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

log = logging.getLogger("sigcore.viewer")

Command = Callable[["Simulation"], "str | None"]
"""What a person asked, run on the simulation thread between steps; returns a note to show, or None."""

UNLOADED = (-1, -1)
"""The layout key while no world is loaded."""

POLL = 0.005
"""Wall seconds between two reads of the person's requests while the simulation runs (a click takes effect within
this and a step)."""

CLOSED_GRACE = 3.0
"""Wall seconds without any browser after which a lingering viewer counts its page as closed (a page that reloads
connects again well within this)."""

OVERLAYS = {"names": True, "frames": False, "scan": False, "contacts": False, "map": True}
"""The overlays and whether each is on at the start."""

PACES: dict[str, float | None] = {"real time": 1.0, "0.25x": 0.25, "0.5x": 0.5, "2x": 2.0, "5x": 5.0,
                                  "10x": 10.0, "as fast as possible": None}
"""The paces a person may pick (simulated seconds per wall second; None: as fast as possible)."""


def pace_name(factor: float | None) -> str:
    """The name of ``factor`` among :data:`PACES`, or ``"<f>x"``."""
    for name, value in PACES.items():
        if value == factor:
            return name
    return f"{factor:g}x"


@dataclass
class Snapshot:
    """What the browser shows at one moment, taken on the simulation thread between two steps.

    Attributes:
        step: The step the poses belong to (``sim.worlds.elapsed_steps``).
        time: Its simulated time [s] (of the loaded world).
        wall: ``time.perf_counter()`` when it was taken [s].
        layout: The scene's frames and visuals when they changed (a spawn, a delete, another world), else None.
        poses: (frames, 7) position [m] and quaternion (w, x, y, z) of every frame of the layout, in its order.
        status: The run's line (time, wall time, real-time factor, state).
        texts: The panel's other texts by key (score lines, events, result, selection, notes).
        agents: The agents a message may go to; entities: those that can be selected.
        scan: (n, 3) lidar hit points in ``world`` [m], or None when the overlay is off.
        contacts: (n, 3) contact markers [m], or None when the overlay is off.
        grid: ``(image (h, w, 3) uint8, width [m], height [m], centre xyz, wxyz)`` of the newest map, or None.
        images: Camera images by topic (h, w, 3) uint8, new since the last snapshot.
        pace: The run's pace (a name of :data:`PACES`).
        exact: Send every frame whose pose changed at all (a recording paused or scrubbed: the scene shows the
            moment exactly), not only those that moved more than :data:`~sigcore_viewer.scenebuild.MOVED`.
        hidden: (frames,) frames to hide (a recording's entity not in the world at that moment), or None.
        timeline: A recording's ``(time [s], playing, speed name)``, or None for a live run.
        ended: The run has ended (:meth:`WebViewer.linger`): the page holds its last moment, the run's controls are
            disabled, and ``texts["table"]`` holds the features' report (the referee's score table).
    """

    step: int
    time: float
    wall: float
    layout: SceneLayout | None
    poses: np.ndarray
    status: str
    texts: dict[str, str]
    agents: list[str]
    entities: list[str]
    scan: np.ndarray | None = None
    contacts: np.ndarray | None = None
    grid: tuple[np.ndarray, float, float, np.ndarray, np.ndarray] | None = None
    images: dict[str, np.ndarray] = field(default_factory=dict)
    pace: str = "real time"
    exact: bool = False
    hidden: np.ndarray | None = None
    timeline: tuple[float, bool, str] | None = None
    ended: bool = False


@dataclass(frozen=True)
class Pushed:
    """The viewer's process handed a snapshot to viser, which sends it to the browsers.

    Attributes:
        step: The snapshot's step.
        taken: When it was taken (:attr:`Snapshot.wall`, ``time.perf_counter()`` of the simulation's process) [s].
        handed: When it was handed to viser, on the same clock (``perf_counter`` is the machine's monotonic clock,
            shared by its processes) [s].
    """

    step: int
    taken: float
    handed: float


class _Displays(PublicationSink):
    """The publications a viewer shows, as they arrive (on the simulation thread): those with a ``display`` hint,
    laser scans, occupancy grids and images. It never names who declared them."""

    LOG_LINES = 200

    def __init__(self) -> None:
        self.values: dict[str, str] = {}
        self.log: list[str] = []
        self.results: dict[str, str] = {}
        self.scans: dict[str, dict[str, Any]] = {}
        self.grid: dict[str, Any] | None = None
        self.grid_version = 0
        self.images: dict[str, dict[str, Any]] = {}
        self.image_versions: dict[str, int] = {}  # never reset: a new image always has a new number

    def declare(self, publication: Publication) -> None:
        pass

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        kind = publication.msg_type
        if publication.display is not None:
            text = publication.display_text(value)
            if publication.display == "value":
                self.values[publication.topic] = text
            elif publication.display == "log":
                self.log.append(text)
                del self.log[:-self.LOG_LINES]
            else:
                self.results[publication.topic] = text
        elif kind == "sensor_msgs/msg/LaserScan":
            self.scans[publication.topic] = value
        elif kind == "nav_msgs/msg/OccupancyGrid":
            self.grid = value
            self.grid_version += 1
        elif kind == "sensor_msgs/msg/Image":
            self.images[publication.topic] = value
            self.image_versions[publication.topic] = self.image_versions.get(publication.topic, 0) + 1

    def withdraw(self, publication: Publication) -> None:
        topic = publication.topic
        for store in (self.values, self.results, self.scans, self.images):
            store.pop(topic, None)

    def restart(self) -> None:
        """The world was reset: the old trial's events and result are no longer shown."""
        self.log.clear()
        self.results.clear()

    def clear(self) -> None:
        """A new world: nothing of the old one is shown."""
        self.values.clear()
        self.log.clear()
        self.results.clear()
        self.scans.clear()
        self.images.clear()
        self.grid = None
        self.grid_version += 1


class WebViewer(Viewer):
    """The browser viewer (viser, in a process of its own). See :class:`sigcore.viewer.Viewer` for the arguments."""

    name = "web"
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
        self._sim: Simulation | None = None
        self._commands: collections.deque[Command] = collections.deque()
        self._displays = _Displays()
        self._layout: SceneLayout | None = None
        self._layout_key: tuple[int, int] | None = None
        self._next_snapshot = 0.0
        self._next_poll = 0.0
        self._due = 0.0  # the earlier of the two: service() does nothing before
        self._selected: str | None = None
        self._notes: list[str] = []
        self._overlays = dict(OVERLAYS)
        self._rtf_window: list[tuple[float, float]] = []  # (wall, elapsed sim time) of recent snapshots
        self._wall0 = 0.0
        self._grid_sent = -1
        self._images_sent: dict[str, int] = {}
        self._probed: dict[str, Any] = {}
        self._probe_cond = threading.Condition()
        self._probe_requests: collections.deque[str] = collections.deque()  # node_pose from another thread
        self._player_thread: threading.Thread | None = None  # the thread playing a recording back
        self._last: Snapshot | None = None  # the newest snapshot taken: what the page holds after the run
        self._clients = 0  # browsers connected now (as the viewer's process reports)
        self.pushed = 0
        """Snapshots the viewer's process has handed to viser, which sends them to the browsers (as reported)."""
        self.push_observers: list[Callable[[Pushed], None]] = []
        """Called on the simulation thread (in :meth:`service`) with each report of a snapshot handed to viser
        (the bench measures the latency with it)."""
        self.snapshot_observers: list[Callable[[Snapshot], None]] = []
        """Called on the simulation thread with each snapshot taken, before it is sent."""

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
            _end(proc)
            ours.close()
            raise ViewerError(f"the viewer's process ended or did not answer within {self.READY_TIMEOUT:g} s "
                              f"(exit code {proc.returncode}; its error is printed above): {e}") from None
        if answer[0] != "ready":
            _end(proc)
            ours.close()
            raise ViewerError(f"the viewer could not listen on {self.host}:{port}: {answer[1]}")
        self._listening = int(answer[1])
        if self._listening != port:
            log.warning("viewer: port %d was taken meanwhile; the viewer listens on port %d", port,
                        self._listening)
        ours.setblocking(False)
        self._proc, self._sock, self._outbox, self._inbox = proc, ours, Outbox(ours), Inbox(ours)

    def start(self, sim: Simulation) -> None:
        self.open()
        self._sim = sim
        self._wall0 = time.perf_counter()
        sim.publications.connect(self._displays)
        sim.events.subscribe("world", self._world_changed, owner=self)
        sim.events.subscribe("reset", lambda _: self._displays.restart(), owner=self)
        self._snapshot(force_layout=True)

    def stop(self) -> None:
        sim = self._sim
        if sim is not None:
            if self.hold_at_end and self._sock is not None:
                self._snapshot()  # the run's last moment: what the page holds until linger() ends
            sim.publications.disconnect(self._displays)
            sim.events.detach(self)
            self._sim = None  # service() after stop() does nothing
        if not self.hold_at_end:
            self.close()

    @property
    def clients(self) -> int:
        """The browsers connected now, as the viewer's process last reported."""
        return self._clients

    def linger(self, ended: str, lines: list[str], seconds: float | None, done: Callable[[], bool]) -> str:
        """See :meth:`sigcore.viewer.Viewer.linger`. The page keeps the run's last moment (the scene, the result,
        the events), with ``ended`` in the run's line and ``lines`` in the panel's "Task" folder; the run's controls
        are disabled and a person's request is answered with a note. "closed" means a browser had been showing it
        and none has been for :data:`CLOSED_GRACE` seconds (a reload is not a close)."""
        try:
            return self._linger(ended, lines, seconds, done)
        finally:
            self.close()

    def _linger(self, ended: str, lines: list[str], seconds: float | None, done: Callable[[], bool]) -> str:
        snap = self._last
        if snap is None or self._sock is None:
            return "gone"
        state = snap.status.split(" · ", 1)[1] if " · " in snap.status else snap.status
        snap.status = f"**ended**: {ended} · {state}"
        snap.texts["table"] = "\n".join(lines)
        snap.texts["notes"] = "the run has ended: this page shows its last moment; press Enter in the terminal " \
            "that runs it, or close this page"
        snap.layout, snap.grid, snap.images, snap.ended = None, None, {}, True
        self._send(("snap", snap))
        end = perf_counter() + seconds if seconds is not None else math.inf
        seen, empty_since = self._clients > 0, None
        while True:
            if done():
                return "done"
            now = perf_counter()
            if now >= end:
                return "time"
            sock, inbox = self._sock, self._inbox
            if sock is None or inbox is None:
                return "gone"
            select.select([sock], [], [], min(0.1, max(0.0, end - now)))
            try:
                messages = inbox.read()
            except (PeerGone, ValueError):
                return "gone"
            for message in messages:
                if not self._report(message):  # the run's controls mean nothing now: say so
                    snap.texts["notes"] = (f"the run has ended ({ended}): nothing to {message[0]}; press Enter in "
                                           "the terminal that runs it, or close this page")
                    self._send(("snap", snap))
            self._flush()
            seen = seen or self._clients > 0
            if self._clients > 0 or not seen:
                empty_since = None
            elif empty_since is None:
                empty_since = now
            elif now - empty_since >= CLOSED_GRACE:
                return "closed"

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
            _end(self._proc)
        self._proc, self._sock, self._outbox, self._inbox, self._listening = None, None, None, None, None

    # ------------------------------------------------------------------ a recording
    def play_recording(self, path: Path, stop: Callable[[], bool]) -> None:
        """Play the recording ``path`` back (``sigcore view DIR``) until ``stop()`` is true: the scene from its
        ground truth, the score, events and result from its publications, and a timeline in the panel (play, pause,
        speed, a slider to scrub, jumps to the start and the end); see :mod:`sigcore_viewer.playback`. Like a live
        run, the playback runs in this process (its clock, the person's requests, a snapshot of the moment at most
        ``rate`` times a second while playing) and the viewer's process shows the snapshots; it never blocks on the
        browsers.

        Raises:
            ViewerError: this viewer shows a running simulation, the recording's world cannot be rebuilt or it holds
                no ground truth (naming the file and what is missing), or the viewer's process ended.
        """
        from . import playback

        if self._sim is not None:
            raise ViewerError("this viewer shows a running simulation: it cannot play a recording as well")
        self.open()
        self._send(("snap", playback.loading(Path(path), perf_counter())))
        self._flush()
        with tempfile.TemporaryDirectory(prefix="sigcore_view_") as workdir:  # the attached world, while shown
            try:
                recorded = playback.load(Path(path), Path(workdir), stop)
            except playback.Interrupted:
                return
            player = playback.Player(recorded, self._overlays)
            self._player_thread = threading.current_thread()
            try:
                self._send(("playback", player.timeline()))
                self._play(player, stop)
            finally:
                self._player_thread = None

    def _play(self, player: Any, stop: Callable[[], bool]) -> None:
        """The playback's loop: wait for the person's requests (at most until the next snapshot is due, or 0.1 s to
        see ``stop()``), act on them, send a snapshot when something changed or, while playing, at ``rate``."""
        interval = 1.0 / self.rate
        next_snapshot = 0.0
        while not stop():
            sock, inbox, outbox = self._sock, self._inbox, self._outbox
            if sock is None or inbox is None or outbox is None:
                deadline = time.monotonic() + 0.5  # a signal to the process group ends both: this one is told too
                while time.monotonic() < deadline:
                    if stop():
                        return
                    time.sleep(0.02)
                code = None
                if self._proc is not None:
                    _end(self._proc)
                    code = self._proc.returncode
                raise ViewerError(f"the viewer's process ended (exit code {code}): nothing shows the recording any "
                                  "more")
            now = perf_counter()
            wait = 0.1
            if player.dirty or player.playing:
                wait = min(wait, max(0.0, next_snapshot - now))
            if not outbox.empty:
                wait = min(wait, 0.005)
            if self._probe_requests:
                wait = 0.0
            select.select([sock], [], [], wait)
            try:
                messages = inbox.read()
            except (PeerGone, ValueError):
                sock.close()  # the viewer's process ended (with this one, at Ctrl-C or a signal: stop() says)
                self._sock, self._outbox, self._inbox = None, None, None
                continue
            for message in messages:
                if not self._report(message):
                    player.request(message, perf_counter())
                    if message[0] == "select" and player.selected is not None:
                        self._send(("selected", player.selected, None))
            while self._probe_requests:
                self._send(("probe", self._probe_requests.popleft()))
            now = perf_counter()
            if (player.dirty or player.playing) and now >= next_snapshot and self._flush():
                next_snapshot = now + interval
                snap = player.snapshot(now)
                for watcher in list(self.snapshot_observers):
                    watcher(snap)
                self._send(("snap", snap))

    # ------------------------------------------------------------------ the simulation thread
    def service(self, timeout: float) -> None:
        """Between two steps: act on the person's requests (the socket is read at most every :data:`POLL` seconds
        unless ``timeout`` asks to wait: a read that finds nothing costs more than a step's share), then take and
        send a snapshot when one is due and the socket took the last one. Called at every step: when nothing is
        due it returns after one clock reading."""
        if timeout <= 0.0 and not self._commands and perf_counter() < self._due:
            return
        sim = self._sim
        if sim is None:
            return
        now = perf_counter()
        if self._sock is not None and (timeout > 0 or now >= self._next_poll):
            self._next_poll = now + POLL
            if timeout > 0 and not self._commands:
                select.select([self._sock], [], [], timeout)
            self._receive(sim)
            self._flush()
        while self._commands:
            self._run(sim, self._commands.popleft())
        if now >= self._next_snapshot and self._flush():  # no room in the socket yet: the next service tries again
            self._next_snapshot = now + 1.0 / self.rate
            self._snapshot()
        self._due = min(self._next_poll, self._next_snapshot)

    def _receive(self, sim: Simulation) -> None:
        """Act on what the viewer's process sent: the person's requests, reports of pushed snapshots."""
        assert self._inbox is not None
        try:
            messages = self._inbox.read()
        except (PeerGone, ValueError) as e:
            self._lost(e)
            return
        for message in messages:
            if not self._report(message):
                self._run(sim, self._request(message))

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

    def _request(self, message: tuple[Any, ...]) -> Command:
        """The command a person's request (from the panel, in the viewer's process) stands for."""
        kind, args = message[0], message[1:]
        simple: dict[str, Command] = {"play": play, "pause": pause, "reset": reset}
        if kind in simple and not args:
            return simple[kind]
        made: dict[str, Callable[..., Command]] = {
            "step": step, "pace": set_pace, "send": send_message, "select": self._select_command,
            "move": self._move_command, "overlay": self._overlay_command}
        if kind in made:
            try:
                return made[kind](*args)
            except TypeError:
                pass
        return lambda sim: f"the viewer sent a request sigcore does not know: {clip(repr(message), 80)}"

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
            _end(self._proc)
        self._sock, self._outbox, self._inbox = None, None, None

    def _post(self, command: Command) -> None:
        """Queue ``command`` to run on the simulation thread at the next :meth:`service`."""
        self._commands.append(command)

    def _run(self, sim: Simulation, command: Command) -> None:
        """Run a person's command; what it answers, or what went wrong, becomes a note (never an exception)."""
        try:
            note = command(sim)
        except ApiError as e:
            note = str(e)
        except Exception as e:  # a bug in a command must not stop the simulation
            log.exception("viewer: a command failed")
            note = f"that did not work: {type(e).__name__}: {clip(str(e))}"
        if note:
            self._note(note)
        self._next_snapshot = self._due = 0.0  # show the effect at once

    def _note(self, text: str) -> None:
        stamp = self._sim.time if self._sim is not None and self._sim.worlds.loaded else 0.0
        self._notes.append(f"t = {stamp:.2f} s: {text}")
        del self._notes[:-5]

    def _world_changed(self, change: Any) -> None:
        if change.kind == "unloading":
            self._displays.clear()
            self._selected = None

    def _snapshot(self, force_layout: bool = False) -> None:
        """Take a snapshot and send it to the viewer's process."""
        sim = self._sim
        assert sim is not None
        wall = time.perf_counter()
        layout = None
        if not sim.worlds.loaded:
            if force_layout or self._layout_key != UNLOADED or self._layout is None:  # once, not at every update
                self._layout, self._layout_key = layout_of(None), UNLOADED
                layout = self._layout
        else:
            key = (id(sim.scene), sim.scene.version)
            if force_layout or key != self._layout_key or self._layout is None:
                self._layout, self._layout_key = layout_of(sim), key
                layout = self._layout
        assert self._layout is not None
        poses = sim.backend.get_poses(self._layout.parts) if sim.worlds.loaded else np.empty((0, 7))
        control = sim.control
        self._rtf_window.append((wall, sim.worlds.elapsed_time))
        while len(self._rtf_window) > 2 and wall - self._rtf_window[0][0] > 2.0:
            self._rtf_window.pop(0)
        (w0, t0), (w1, t1) = self._rtf_window[0], self._rtf_window[-1]
        rtf = (t1 - t0) / (w1 - w0) if w1 - w0 > 0.2 else float("nan")
        state = ("no world loaded" if not sim.worlds.loaded else "stopping" if control.stopping else
                 "paused" if control.paused else
                 f"running ({pace_name(control.realtime_factor)})")
        rtf_text = "–" if math.isnan(rtf) else f"{rtf:.2f}"
        status = (f"**{state}** · world `{sim.world.name}` · t = {sim.time:.2f} s · step {sim.step_count} · "
                  f"wall {wall - self._wall0:.1f} s · real-time factor {rtf_text}")
        d = self._displays
        texts = {
            "score": "  \n".join(d.values.values()) or "no score in this world",
            "events": "  \n".join(reversed(d.log[-15:])) or "no events yet",
            "result": "  \n".join(d.results.values()),
            "selection": self._describe(sim, self._selected),
            "notes": "  \n".join(reversed(self._notes)),
        }
        snap = Snapshot(sim.worlds.elapsed_steps, sim.time, wall, layout, poses, status, texts,
                        list(sim.entities) if sim.worlds.loaded else [],
                        list(sim.entities.names) if sim.worlds.loaded else [], pace=pace_name(control.realtime_factor))
        if sim.worlds.loaded:
            if self._overlays["scan"]:
                snap.scan = self._scan_points(poses)
            if self._overlays["contacts"]:
                snap.contacts = self._contact_points(sim)
            if d.grid is not None and d.grid_version != self._grid_sent:
                snap.grid = _grid_image(d.grid)
                self._grid_sent = d.grid_version
            for topic, value in d.images.items():
                if self._images_sent.get(topic) != d.image_versions[topic]:
                    self._images_sent[topic] = d.image_versions[topic]
                    image = _image(value)
                    if image is not None:
                        snap.images[topic] = image
        for observer in list(self.snapshot_observers):
            observer(snap)
        self._last = snap
        self._send(("snap", snap))

    def _describe(self, sim: Simulation, name: str | None) -> str:
        """The state of the selected entity (pose, velocity, tags, who grasps it, joint angles)."""
        if name is None:
            return "click an entity, or pick one above"
        if not sim.worlds.loaded or name not in sim.entities:
            return f"{quote(name)} is gone (deleted, or another world)"
        handle = sim.entities[name]
        lines = [f"**{name}** ({handle.kind})"]
        try:
            pos, quat = sim.backend.get_pose(name)
            lines.append(f"position: {pos[0]:.3f} {pos[1]:.3f} {pos[2]:.3f} m")
            w, x, y, z = quat
            yaw = math.degrees(quat_yaw(quat))
            lines.append(f"orientation (w x y z): {w:.3f} {x:.3f} {y:.3f} {z:.3f} (yaw {yaw:.1f}°)")
            v = handle.velocity()
            lines.append(f"velocity: {v[0]:.3f} {v[1]:.3f} {v[2]:.3f} m/s")
        except ApiError:
            pass
        info = sim.entities.info.get(name) if name in sim.entities.info.names else None
        if info is not None:
            lines.append(f"category: {info.category}; tags: {', '.join(info.tags) or 'none'}")
        held = sim.entities.grasps.held_by(name)
        if held is not None:
            lines.append(f"grasped by: {held[0]} ({held[1]})")
        holding = [f"{obj} in {part}" for robot, part, obj in sim.entities.grasps.items() if robot == name]
        if holding:
            lines.append(f"holding: {', '.join(holding)}")
        if isinstance(handle, RobotObj):
            angles = handle.all_joint_angles()
            if angles:
                lines.append("joints [rad]: " + ", ".join(f"{j} {a:.2f}" for j, a in angles.items()))
        return "  \n".join(lines)

    def _scan_points(self, poses: np.ndarray) -> np.ndarray:
        """The newest scan of every lidar as world points, from the pose of its frame in this snapshot."""
        assert self._layout is not None
        return scan_points(self._layout, self._displays.scans.values(), poses)

    def _contact_points(self, sim: Simulation) -> np.ndarray:
        """A marker at each part touching another entity (the floor contacts of wheels and casters left out)."""
        points = []
        for entity, part, other in sim.contact_triples():
            if other == "ground" and sim.entities.is_robot(entity) and part in sim.entities.rolling_parts(entity):
                continue
            try:
                pos, _ = sim.backend.get_pose(entity, None if part == "main" else part)
            except Exception:  # a part the backend no longer has (deleted meanwhile): no marker
                continue
            points.append(pos)
        return np.array(points, dtype=float).reshape(-1, 3)

    # ------------------------------------------------------------------ the person's selection, drags, overlays
    def _select_command(self, name: str) -> Command:
        return lambda sim: self.select(sim, name)

    def _move_command(self, name: str, position: Any, wxyz: Any) -> Command:
        def run(sim: Simulation) -> str | None:
            note = move_entity(name, np.asarray(position, dtype=float), np.asarray(wxyz, dtype=float))(sim)
            if note is not None and name in sim.entities:
                self._send(("selected", name, self._drag_pose(sim, name)))  # the handle goes back where it is
            return note
        return run

    def _overlay_command(self, key: str, on: bool) -> Command:
        def run(sim: Simulation) -> str | None:
            if key not in self._overlays:
                return f"unknown overlay {quote(str(key))}; valid: {', '.join(self._overlays)}"
            self._overlays[key] = bool(on)
            return None
        return run

    def select(self, sim: Simulation, name: str) -> str | None:
        """Select entity ``name`` (its state is shown and the drag handle attached to it)."""
        if name not in sim.entities:
            return f"no entity {quote(name)} to select; entities: {', '.join(sim.entities.names) or 'none'}"
        self._selected = name
        self._send(("selected", name, self._drag_pose(sim, name)))
        return None

    def _drag_pose(self, sim: Simulation, name: str) -> tuple[list[float], list[float]] | None:
        try:
            pos, quat = sim.backend.get_pose(name)
        except Exception:
            return None
        return [float(x) for x in pos], [float(x) for x in quat]

    def set_overlay(self, key: str, on: bool) -> None:
        """Turn an overlay on or off (``names``, ``frames``, ``scan``, ``contacts``, ``map``); the panel's switch
        follows.

        Raises:
            ViewerError: ``key`` is no overlay.
        """
        if key not in self._overlays:
            raise ViewerError(f"unknown overlay {key!r}; valid: {', '.join(self._overlays)}")
        self._overlays[key] = on
        self._next_snapshot = self._due = 0.0
        self._send(("overlay", key, on))

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


# ------------------------------------------------------------------ the person's commands
def play(sim: Simulation) -> str | None:
    try:
        sim.control.play()
    except RunStateError as e:
        return str(e)
    return None


def pause(sim: Simulation) -> str | None:
    sim.control.pause()
    return None


def step(n: Any) -> Command:
    def run(sim: Simulation) -> str | None:
        try:
            value = float(n)
        except (TypeError, ValueError):
            return f"steps must be a whole number from 1 to 100000, got {quote(str(n))}"
        if not value.is_integer() or not (1 <= value <= 100000):
            return f"steps must be a whole number from 1 to 100000, got {n}"
        try:
            sim.control.step(int(value))
        except RunStateError as e:
            return str(e)
        return None
    return run


def reset(sim: Simulation) -> str | None:
    held = sim.entities.grasps.items() if sim.worlds.loaded else []
    try:
        sim.control.request_reset()
    except RunStateError as e:
        return str(e)
    if held:
        released = "; ".join(f"{robot} let go of {obj}" for robot, _, obj in held)
        return f"reset to the start: {released}"
    return "reset to the start"


def set_pace(name: str) -> Command:
    def run(sim: Simulation) -> str | None:
        if name not in PACES:
            return f"unknown pace {quote(name)}; valid: {', '.join(PACES)}"
        sim.control.set_pace(PACES[name])
        return None
    return run


def send_message(agent: str, text: str) -> Command:
    def run(sim: Simulation) -> str | None:
        if not agent:
            return "pick an agent to send the message to"
        if not text.strip():
            return "type a message first"
        if agent not in sim.entities:
            return (f"agent {quote(agent)} no longer exists: the message was not sent; agents: "
                    f"{', '.join(sim.entities) or 'none'}")
        sim.inputs.message(VIEWER_SENDER, agent, text)
        return f"sent to {agent}: {clip(text, 80)}"
    return run


def move_entity(name: str, position: np.ndarray, wxyz: np.ndarray) -> Command:
    """Teleport ``name`` through the API entries ``_setPosition`` and ``_setRotation`` (what a ROS client calls)."""
    def run(sim: Simulation) -> str | None:
        if name not in sim.entities:
            return f"{quote(name)} no longer exists: nothing was moved"
        model = next((e for e in sim.world.entities if e.name == name), None)
        if isinstance(model, Object) and model.static:
            return (f"{name} is static (fixed in place): it cannot be dragged; movable objects, robots and people "
                    "can")
        entries = {e.suffix: e for e in sim.api_entries()}
        p, q = [float(v) for v in position], [float(v) for v in wxyz]
        if not all(math.isfinite(x) for x in p + q) or not any(q):
            return (f"{name} was not moved: the position {p} [m] and the quaternion (w x y z) {q} must be finite "
                    "numbers, the quaternion non-zero")
        requests = [("_setPosition", {"name": name, "x": p[0], "y": p[1], "z": p[2]}),
                    ("_setRotation", {"name": name, "qw": q[0], "qx": q[1], "qy": q[2], "qz": q[3]})]
        if isinstance(model, Object) and sim.entities.mode(name, "dynamics"):  # put down at rest, not thrown
            requests += [("_setVelocity", {"name": name}), ("_setAngularVelocity", {"name": name})]
        for suffix, request in requests:
            answer = call(sim, entries[suffix], name, request)
            if isinstance(answer, dict) and not answer.get("success", False):
                return f"{name} was not moved: {answer.get('message', '')}"
        return None
    return run


# ------------------------------------------------------------------ helpers
def scan_points(layout: SceneLayout, scans: Iterable[dict[str, Any]], poses: np.ndarray) -> np.ndarray:
    """``sensor_msgs/LaserScan`` values as (n, 3) world points, each from the pose of its frame in ``poses`` (the
    layout's frames); scans of a frame the layout has not are left out."""
    out = [np.zeros((0, 3))]
    for scan in scans:
        index = layout.index.get(str(scan.get("header", {}).get("frame_id", "")))
        if index is None:
            continue
        ranges = np.asarray(scan["ranges"], dtype=float)
        angles = scan["angle_min"] + scan["angle_increment"] * np.arange(len(ranges))
        ok = np.isfinite(ranges) & (ranges < scan["range_max"]) & (ranges >= scan["range_min"])
        local = np.stack([ranges[ok] * np.cos(angles[ok]), ranges[ok] * np.sin(angles[ok]),
                          np.zeros(int(ok.sum()))], axis=1)
        out.append(local @ quat_to_matrix(poses[index, 3:]).T + poses[index, :3])
    return np.vstack(out)


def _stderr() -> int:
    """This process's stderr as a file descriptor for a child's stdout (nowhere when stderr is no file, e.g. under
    a test's capture: the run's stdout is for its results)."""
    try:
        return sys.stderr.fileno()
    except (AttributeError, OSError, ValueError):
        return subprocess.DEVNULL


def _end(proc: subprocess.Popen[bytes]) -> None:
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


def _grid_image(grid: dict[str, Any]) -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray] | None:
    """An occupancy grid as a floor image: free white, occupied black, unknown grey."""
    info = grid.get("info", {})
    w, h, res = int(info.get("width", 0)), int(info.get("height", 0)), float(info.get("resolution", 0.0))
    data = np.asarray(grid.get("data", []), dtype=np.int16)
    if w <= 0 or h <= 0 or res <= 0 or data.size != w * h:
        return None
    cells = data.reshape(h, w)
    shade = np.where(cells < 0, 200, 255 - (np.clip(cells, 0, 100) * 255 // 100)).astype(np.uint8)
    image = np.repeat(np.flipud(shade)[:, :, None], 3, axis=2)  # row 0 of the grid is at the origin's y
    origin = info.get("origin", {})
    p, o = origin.get("position", {}), origin.get("orientation", {})
    quat = np.array([o.get("w", 1.0), o.get("x", 0.0), o.get("y", 0.0), o.get("z", 0.0)], dtype=float)
    centre = np.array([p.get("x", 0.0), p.get("y", 0.0), p.get("z", 0.0)]) + \
        quat_to_matrix(quat) @ np.array([w * res / 2, h * res / 2, 0.0])
    centre[2] += 0.003  # just above the floor
    return image, w * res, h * res, centre, quat


def _image(value: dict[str, Any]) -> np.ndarray | None:
    """A ``sensor_msgs/Image`` (rgb8, bgr8, mono8 or 32FC1 depth) as an RGB array; None for other encodings."""
    h, w, encoding = int(value.get("height", 0)), int(value.get("width", 0)), str(value.get("encoding", ""))
    data = value.get("data")
    if h <= 0 or w <= 0 or data is None:
        return None
    raw = np.frombuffer(bytes(data) if not isinstance(data, np.ndarray) else data.tobytes(), dtype=np.uint8)
    if encoding in ("rgb8", "bgr8") and raw.size == h * w * 3:
        image = raw.reshape(h, w, 3)
        return image[:, :, ::-1] if encoding == "bgr8" else image
    if encoding == "mono8" and raw.size == h * w:
        return np.repeat(raw.reshape(h, w, 1), 3, axis=2)
    if encoding == "32FC1" and raw.size == h * w * 4:
        depth = raw.view(np.float32).reshape(h, w)
        finite = np.isfinite(depth)
        top = float(depth[finite].max()) if finite.any() else 1.0
        gray = np.where(finite, 255 - np.clip(depth / max(top, 1e-6), 0, 1) * 255, 0).astype(np.uint8)
        return np.repeat(gray[:, :, None], 3, axis=2)
    return None
