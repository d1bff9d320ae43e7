"""The viewer interface: a window on a running simulation for a person, with SIGViewer's controls.

A viewer is a :class:`~sigcore.transport.Transport` without named endpoints: :func:`sigcore.sim.run` starts it
beside the transport (``sigcore run WORLD --viewer``, ``sigcore view WORLD``) and services it between steps, so
what a person does (pause, step, reset, the pace, a message to an agent, a dragged object) reaches the simulation
on its own thread, between steps, through the same API a ROS 2 client uses. What it shows it reads from the core's
contracts only: the scene description (``sim.scene``), the backend's poses read between steps, the declared
publications (:mod:`sigcore.publish`; a publication's ``display`` says how a viewer shows it) and the run's
control (``sim.control``). It never names a feature. Plugins register viewers with ``sigcore_register_viewers``.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from .errors import ViewerError
from .transport import Endpoint, Transport

if TYPE_CHECKING:
    from .sim.simulation import Simulation
    from .world.exceptions import WorldIssue

DEFAULT_VIEWER = "web"
"""The viewer ``sigcore run --viewer`` and ``sigcore view`` start (the ``sigcore-viewer`` distribution's)."""

DEFAULT_PORT = 8080
"""The port a viewer listens on when none is given (the next free one when it is taken)."""

VIEWER_SENDER = "viewer"
"""The sender of the messages a person sends to an agent from a viewer (``on_recv_msg``, ``<agent>_onRecvMsg``)."""


class Viewer(Transport):
    """A transport for a person: shows the world live and takes a person's controls.

    Args:
        host: The address to listen on (``127.0.0.1``: this machine only; ``0.0.0.0``: every interface).
        port: The port; None: :data:`DEFAULT_PORT`, or the next free one when it is taken (said at start). A port
            given explicitly that is taken is refused with :class:`ViewerError`.
        rate: Updates of the scene per second of wall time [Hz], at most (0 < rate <= 120).

    Raises:
        ViewerError: ``rate`` is out of range or ``port`` not in 1..65535.
    """

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, rate: float = 30.0) -> None:
        if not (0 < rate <= 120):
            raise ViewerError(f"viewer rate {rate!r} Hz is out of range; valid: 0 < rate <= 120 (e.g. 30)")
        if port is not None and not (1 <= port <= 65535):
            raise ViewerError(f"viewer port {port} is out of range; valid: 1..65535 (default {DEFAULT_PORT})")
        self.host = host
        self.port = port
        self.rate = rate

    @property
    @abstractmethod
    def url(self) -> str:
        """Where a browser opens the viewer (known once :meth:`open` returned)."""

    @abstractmethod
    def open(self) -> None:
        """Start listening before the simulation starts (``sigcore run`` calls it before the run, so that a taken
        port is refused with exit 2 and the URL is known); :meth:`start` calls it when it was not called.

        Raises:
            ViewerError: it cannot listen as asked (the port is taken...).
        """

    def play_recording(self, path: Path, stop: Callable[[], bool]) -> None:
        """Show the recording ``path`` (a bag directory made by ``sigcore run --record``, already checked with
        :func:`sigcore.record.bag_info`) instead of a running simulation (``sigcore view DIR``): the scene from its
        ground truth, the texts from its publications at each moment, with a timeline the person can scrub. Called
        after :meth:`open`; returns when ``stop()`` is true (Ctrl-C). Default: a viewer that cannot.

        Raises:
            ViewerError: this viewer cannot show recordings, or this one cannot be shown (naming why).
        """
        raise ViewerError(f"viewer '{self.name}' cannot show recordings")

    hold_at_end: bool = False
    """Set before the run (``sigcore run --viewer-linger``): :meth:`stop` then leaves the page up, showing the run's
    last moment, until :meth:`linger` ends (or :meth:`close`)."""

    def linger(self, ended: str, lines: list[str], seconds: float | None, done: Callable[[], bool]) -> str:
        """After a run stopped with :attr:`hold_at_end`: show how it ended (``ended``, one line) and the features'
        report (``lines``: the referee's score table) beside the last moment, and keep the page up until ``done()``
        is true, ``seconds`` [s of wall time] have passed (None: no limit), or the last browser showing it closed;
        then :meth:`close`. Returns why it ended: ``"done"``, ``"time"``, ``"closed"`` or ``"gone"`` (the viewer
        itself ended). Default: a viewer with nothing to keep up (``"gone"``)."""
        self.close()
        return "gone"

    def close(self) -> None:
        """End a viewer held open by :attr:`hold_at_end` after :meth:`stop` (nothing otherwise)."""

    def plan(self, sim: Simulation) -> list[Endpoint]:
        """A viewer creates no named endpoints."""
        return []

    def check(self, sim: Simulation) -> list[WorldIssue]:
        """Nothing to check: no named endpoints."""
        return []
