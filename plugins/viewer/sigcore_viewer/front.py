"""The viewer's own process: viser's web server, the 3D scene and the panel, fed with snapshots by the simulation.

:class:`~sigcore_viewer.viewer.WebViewer` starts it (``python -m sigcore_viewer.front``) with one end of a Unix
socket pair. Nothing here runs on the simulation's interpreter, so serving the page and sending updates to the
browsers never holds the simulation's GIL: the simulation's process only takes the snapshot (well under a
millisecond) and writes it to the socket. Three threads:

* the **main thread** reads the simulation's messages: snapshots (into a one-snapshot mailbox: one the push thread
  had no time for is replaced by the next, what it carried that is shown once - a new layout, a map, images - kept),
  the selected entity, overlay switches, probes of a node's pose, a recording's timeline (``sigcore view DIR``: the
  panel turns into a player), ``stop``;
* the **push thread** turns the newest snapshot into viser updates (only what changed is sent) and reports each
  as pushed;
* **viser's threads** serve the page and call the panel's callbacks, which send the person's requests to the
  simulation as plain tuples (names and numbers).

Whatever changes viser's state (the scene, the panel) runs on **viser's event-loop thread**, handed over by
:meth:`Front.on_viser`, never on the two threads above. viser wakes its senders with an ``asyncio.Event`` that it
sets from whichever thread queued the message; set from another thread, in the few instructions between a sender's
"is it set?" and its registration as a waiter, the wake-up is lost and that sender sleeps for good: the page keeps its
last picture while the run goes on (1 CI run in 5 of the README's viewer test, under load; reproduced with the window
widened in ``tests/viewer/test_viewer_front.py``).

When the simulation's process ends (its end of the socket closes) this process stops its server and ends too.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import faulthandler
import io
import logging
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from . import wire
from .panel import Panel
from .scenebuild import SceneNodes

if TYPE_CHECKING:
    from .snapshot import Snapshot

log = logging.getLogger("sigcore.viewer")

HANDOVER = 60.0
"""At most this long [s] for viser's event loop to run what :meth:`Front.on_viser` hands it (a push is milliseconds;
a loop that stopped, the server shutting down, is an error)."""

STUCK = 30.0
"""A push that takes longer than this [s] prints every thread's stack to stderr (a viewer whose page stopped
updating says where it hangs)."""

AMBIENT = 1.2
"""The ambient light's intensity, in place of viser's environment map: the colours as bright as with it."""

Post = Callable[[tuple[Any, ...]], None]
"""Sends a request to the simulation's process."""


class Front:
    """The browser's side of one viewer on ``server``.

    Args:
        server: A started ``viser.ViserServer``.
        post: Sends a request to the simulation (``("play",)``, ``("select", name)``, ``("pushed", ...)``...).
        overlays: The overlay switches at the start (the simulation's process keeps the same).
    """

    def __init__(self, server: Any, post: Post, overlays: dict[str, bool]) -> None:
        self._server = server
        self._loop = server.get_event_loop()
        self._loop_thread: int | None = None
        self._loop_thread = self.on_viser(threading.get_ident)
        self._post = post
        self._overlays = dict(overlays)
        # a page left open on this port reconnects as soon as the server listens: even the scene's set-up goes
        # through viser's thread
        self.nodes, self.panel = self.on_viser(self._build)
        self._mailbox: Snapshot | None = None
        self._wake = threading.Condition()
        self._stopping = False
        self.failures = 0
        """Snapshots the push thread failed to send (logged: the first, then every 100th)."""
        self._pusher = threading.Thread(target=self._push_loop, name="sigcore-viewer-push", daemon=True)
        self._pusher.start()
        # how many browsers are connected: a lingering viewer ends when the last one closed
        server.on_client_connect(lambda _client: self._count())
        server.on_client_disconnect(lambda _client: self._count())

    def _build(self) -> tuple[SceneNodes, Panel]:
        server, post = self._server, self._post
        server.scene.set_up_direction("+z")
        # software WebGL (a server or a laptop without a GPU) took seconds to turn viser's default environment map
        # (an HDR image) into lighting, with the page frozen meanwhile: an ambient light lights the scene instead
        # (bench/viewer_first_paint.py, docs/viewer.md "The first picture")
        server.scene.configure_environment_map(hdri=None)
        server.scene.add_light_ambient("/sigcore_ambient", intensity=AMBIENT)
        server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        nodes = SceneNodes(server, lambda name: post(("select", name)))
        return nodes, Panel(server, post, self._overlays, self.on_viser)

    def _count(self) -> None:
        self._post(("clients", len(self._server.get_clients())))

    def receive(self, message: tuple[Any, ...]) -> bool:
        """Act on one message of the simulation's process; False when it says stop."""
        kind = message[0]
        if kind == "snap":
            self._deliver(message[1])
        elif kind == "selected":
            _, name, pose = message
            self.on_viser(self.panel.selected, name, pose)
        elif kind == "overlay":
            _, key, on = message
            self._overlays[key] = bool(on)
            self.on_viser(self.panel.show_switch, key, bool(on))
        elif kind == "probe":
            self._post(("probed", message[1], self.node_pose(message[1])))
        elif kind == "playback":
            self.on_viser(self.panel.playback, message[1])
        elif kind == "stop":
            return False
        else:
            log.warning("viewer: an unknown message %r from the simulation's process was ignored", kind)
        return True

    def node_pose(self, name: str) -> tuple[list[float], list[float]] | None:
        """The position and orientation (w, x, y, z) viser holds for scene node ``name`` (what the browsers are
        sent; relative to its parent node), or None when there is no such node."""
        try:
            handle = self._server.scene.get_handle_by_name(name)
        except Exception:
            return None
        if handle is None:
            return None
        return [float(x) for x in handle.position], [float(x) for x in handle.wxyz]

    def _deliver(self, snap: Snapshot) -> None:
        with self._wake:
            previous = self._mailbox
            if previous is not None:  # what the push thread has not shown yet, and is shown once, is kept
                if snap.layout is None:
                    snap.layout = previous.layout
                if snap.grid is None:
                    snap.grid = previous.grid
                for topic, image in previous.images.items():
                    snap.images.setdefault(topic, image)  # the newer image wins
            self._mailbox = snap
            self._wake.notify()

    def _push_loop(self) -> None:
        while True:
            with self._wake:
                while self._mailbox is None and not self._stopping:
                    self._wake.wait()
                if self._stopping:
                    return
                snap, self._mailbox = self._mailbox, None
            assert snap is not None
            faulthandler.dump_traceback_later(STUCK)
            try:
                self.push(snap)
            except Exception:  # a browser or viser failure must not stop the viewer: log and go on
                self.failures += 1
                if self.failures == 1 or self.failures % 100 == 0:
                    log.exception("viewer: sending an update failed (%d so far; the simulation goes on)",
                                  self.failures)
                time.sleep(0.1)
            finally:
                faulthandler.cancel_dump_traceback_later()

    def push(self, snap: Snapshot) -> None:
        """Send what changed in ``snap`` to the browsers (on viser's event-loop thread), then report it pushed."""
        self.on_viser(self._show, snap)
        self._post(("pushed", snap.step, snap.wall, time.perf_counter()))

    def _show(self, snap: Snapshot) -> None:
        with self._server.atomic():
            if snap.layout is not None:
                self.nodes.build(snap.layout, self._overlays, snap.poses)
            self.nodes.move(snap.poses, self._overlays["frames"], snap.exact)
            self.nodes.hide(snap.hidden)
            self.nodes.overlays(snap, self._overlays)
            self.panel.update(snap)

    def on_viser(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Run ``fn(*args)`` on viser's event-loop thread and wait for it: what it returns, or raises.

        Raises:
            RuntimeError: viser's event loop is closed, or did not run ``fn`` within :data:`HANDOVER` seconds.
        """
        if threading.get_ident() == self._loop_thread:  # already there (a callback viser runs on its loop)
            return fn(*args)
        done: concurrent.futures.Future[Any] = concurrent.futures.Future()

        def run() -> None:
            if not done.set_running_or_notify_cancel():
                return
            try:
                done.set_result(fn(*args))
            except BaseException as e:  # handed back to the waiting thread
                done.set_exception(e)

        self._loop.call_soon_threadsafe(run)  # RuntimeError when the loop is closed
        try:
            return done.result(timeout=HANDOVER)
        except concurrent.futures.TimeoutError:
            done.cancel()
            raise RuntimeError(f"viser's event loop did not run {getattr(fn, '__name__', fn)!r} within "
                               f"{HANDOVER:g} s") from None

    def stop(self) -> None:
        with self._wake:
            self._stopping = True
            self._wake.notify_all()
        self._pusher.join(timeout=5.0)


def main(argv: list[str] | None = None) -> int:
    """The viewer's process: ``python -m sigcore_viewer.front --fd FD --host HOST --port PORT``."""
    parser = argparse.ArgumentParser(prog="python -m sigcore_viewer.front",
                                     description="the web viewer's server (started by sigcore's WebViewer)")
    parser.add_argument("--fd", type=int, required=True, help="this process's end of the socket pair")
    parser.add_argument("--host", required=True)
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--overlay", action="append", default=[], help="KEY=0|1: an overlay switch at the start")
    args = parser.parse_args(argv)
    # Ctrl-C reaches the whole process group: the simulation's process stops this one (or its end closes)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.basicConfig(level=logging.WARNING, format="sigcore viewer: %(message)s", stream=sys.stderr)
    # a connection that is no websocket (a port probe) is no error; a failure serving a browser is
    logging.getLogger("websockets.server").addFilter(
        lambda record: record.getMessage() != "opening handshake failed")
    sock = socket.socket(fileno=args.fd)
    sock.setblocking(True)
    lock = threading.Lock()

    def post(message: tuple[Any, ...]) -> None:
        try:
            with lock:
                sock.sendall(wire.encode(message))
        except OSError:  # the simulation's process is gone: the main thread sees it and ends this one
            pass

    try:
        import viser

        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its own banner; sigcore says the URL
            server = viser.ViserServer(host=args.host, port=args.port, label="sigcore", verbose=False)
    except Exception as e:
        post(("error", f"{type(e).__name__}: {e}"))
        return 1
    overlays = {key: value == "1" for key, value in (item.split("=", 1) for item in args.overlay)}
    front = Front(server, post, overlays)
    post(("ready", server.get_port()))
    try:
        while True:
            message = wire.receive(sock)
            try:
                if not front.receive(message):
                    break
            except Exception:  # a failure to show one thing must not end the viewer: log it and go on
                log.exception("viewer: showing %r failed (the viewer goes on)", message[0])
    except wire.PeerGone:
        pass
    finally:
        front.stop()
        try:
            with contextlib.redirect_stdout(io.StringIO()):
                server.stop()
        except Exception:  # viser's own shutdown; nothing is left to save
            log.debug("viewer: stopping viser raised", exc_info=True)
        sock.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
