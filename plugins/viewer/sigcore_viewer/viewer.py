"""The web viewer: a :class:`sigcore.viewer.Viewer` serving the world live to any browser through viser; here its
life (start, stop, the page kept up after the run, a recording played back) and its servicing between steps.

Two processes, so that the browser's side never takes the simulation's interpreter (its GIL):

* in the **simulation's process**, :class:`WebViewer` is serviced between steps. It runs the person's requests
  (:mod:`sigcore_viewer.commands`; they arrive from the viewer's process) and, at most ``rate`` times a second of
  wall time, takes a :class:`~sigcore_viewer.snapshot.Snapshot` (:mod:`sigcore_viewer.snapshot`) - every frame's
  pose read from the backend, the run's state, the texts to show - and writes it to a Unix socket without ever
  blocking (a snapshot the socket has no room for is not taken; the next one is). Nothing else of the viewer touches
  the simulation;
* the **viewer's process** (:mod:`sigcore_viewer.front`, started by :meth:`WebViewer.open`:
  :mod:`sigcore_viewer.link`) runs viser's server, the scene and the panel: it turns the newest snapshot into viser
  updates (only what changed is sent; one it had no time for is replaced by the next, so a slow browser never slows
  the simulation) and sends the person's controls back as plain requests. It ends with the simulation's process.

A recording (``sigcore view DIR``, :meth:`WebViewer.play_recording`) is shown the same way: the playback
(:mod:`sigcore_viewer.playback`: its clock and the moment's snapshot, from the recorded ground truth and publications)
takes the simulation's place in this process, and the viewer's process shows its snapshots with a timeline.
"""

from __future__ import annotations

import collections
import logging
import math
import select
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from time import perf_counter
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.agent.exceptions import ApiError
from sigcore.errors import ViewerError
from sigcore.text import clip, quote

from .commands import Command, command_of, move_entity, switch_overlay
from .exceptions import PeerGone
from .link import FrontLink, end_process
from .snapshot import LiveSnapshots, Snapshot

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

log = logging.getLogger("sigcore.viewer")

POLL = 0.005
"""Wall seconds between two reads of the person's requests while the simulation runs (a click takes effect within
this and a step)."""

CLOSED_GRACE = 3.0
"""Wall seconds without any browser after which a lingering viewer counts its page as closed (a page that reloads
connects again well within this)."""


class WebViewer(FrontLink):
    """The browser viewer (viser, in a process of its own: :class:`~sigcore_viewer.link.FrontLink`). See
    :class:`sigcore.viewer.Viewer` for the arguments."""

    name = "web"

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, rate: float = 30.0) -> None:
        super().__init__(host, port, rate)
        self._sim: Simulation | None = None
        self._commands: collections.deque[Command] = collections.deque()
        self._live = LiveSnapshots()  # the publications shown, what the last snapshot sent
        self._next_snapshot = 0.0
        self._next_poll = 0.0
        self._due = 0.0  # the earlier of the two: service() does nothing before
        self._selected: str | None = None
        self._notes: list[str] = []
        self._last: Snapshot | None = None  # the newest snapshot taken: what the page holds after the run
        self.snapshot_observers: list[Callable[[Snapshot], None]] = []
        """Called on the simulation thread with each snapshot taken, before it is sent."""

    def start(self, sim: Simulation) -> None:
        self.open()
        self._sim = sim
        self._live.wall0 = time.perf_counter()
        sim.publications.connect(self._live.displays)
        sim.events.subscribe("world", self._world_changed, owner=self)
        sim.events.subscribe("reset", lambda _: self._live.displays.restart(), owner=self)
        self._snapshot(force_layout=True)

    def stop(self) -> None:
        sim = self._sim
        if sim is not None:
            if self.hold_at_end and self._sock is not None:
                self._snapshot()  # the run's last moment: what the page holds until linger() ends
            sim.publications.disconnect(self._live.displays)
            sim.events.detach(self)
            self._sim = None  # service() after stop() does nothing
        if not self.hold_at_end:
            self.close()

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
                    end_process(self._proc)
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

    def _request(self, message: tuple[Any, ...]) -> Command:
        """The command a person's request (from the panel, in the viewer's process) stands for."""
        return command_of(message, self._select_command, self._move_command, self._overlay_command)

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
            self._live.displays.clear()
            self._selected = None

    def _snapshot(self, force_layout: bool = False) -> None:
        """Take a snapshot and send it to the viewer's process."""
        sim = self._sim
        assert sim is not None
        snap = self._live.take(sim, self._selected, self._notes, self._overlays, force_layout)
        for observer in list(self.snapshot_observers):
            observer(snap)
        self._last = snap
        self._send(("snap", snap))

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
        return switch_overlay(self._overlays, key, on)

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
