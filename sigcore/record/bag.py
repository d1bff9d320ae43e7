"""rosbag2 directories with MCAP storage, written by :class:`BagWriter` (read by :mod:`sigcore.record.bag_reading`).

A bag is a directory holding ``metadata.yaml`` (rosbag2 version 9, ROS 2 Jazzy: topics with their types, RIHS01
type hashes, offered QoS and message counts) and one MCAP file ``<dir>_0.mcap`` (profile ``ros2``, CDR messages,
``ros2msg`` schemas, zstd-compressed chunks, the offered QoS in each channel's metadata as rosbag2 writes it), so
``ros2 bag info``, ``ros2 bag play`` and Foxglove open it. Files that make a recording self-contained (the world file,
its URDFs) are MCAP attachments; facts about the run are an MCAP metadata record.

A write that fails (a full disk, a file size limit) stops the recording, never the run: the MCAP file is cut back to
the last record written whole and closed there (a data end and a footer, no summary section: readers scan it), and
``metadata.yaml`` counts what the file holds. The file is written by a process of its own
(:mod:`sigcore.record._writer`), which closes the recording when the run is killed. A recording whose writer was
killed before it ended has no ``metadata.yaml``; ``bag_info`` says so and how many messages are readable.
"""

from __future__ import annotations

import contextlib
import fcntl
import logging
import shutil
import subprocess
import sys
import threading
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..publish import Offered
from . import _writer
from .exceptions import BagError

log = logging.getLogger("sigcore.record")

MAX_QUEUED = 20_000
"""Messages that may wait for the sending thread; beyond, the simulation thread sends them itself (and waits for
the writer when it is behind)."""
WRITE_PERIOD = 0.05
"""How often queued messages go to the writer process [s of wall time]."""
CLOSE_TIMEOUT = 120.0
"""How long closing waits for the writer process to finish the file [s]."""
_PIPE_SIZE = 1 << 20
"""The pipe to the writer holds this much (Linux's default limit for a user), so the simulation rarely waits."""

BAG_FILES = ("metadata.yaml",)
"""Besides ``*.mcap``, what a bag directory holds (``--overwrite`` removes a directory with nothing else)."""


@dataclass
class _Topic:
    """A recorded topic as the simulation's side knows it: its index in the writer process, the messages handed
    over (its type, hash and QoS went to the writer with the index)."""

    name: str
    channel: int
    count: int = 0


@dataclass
class BagWriter:
    """Writes one rosbag2 directory (MCAP storage).

    The simulation's thread only queues each message (its topic, log time and bytes). A thread of this process
    sends what is queued every :data:`WRITE_PERIOD` to a writer process of its own (:mod:`sigcore.record._writer`),
    which builds and compresses the MCAP chunks on the other core and writes ``metadata.yaml`` at the close.

    Args:
        path: The directory to create.
        overwrite: Replace ``path`` if it exists and holds a bag (``metadata.yaml`` and ``.mcap`` files only).

    Raises:
        BagError: ``path`` exists (without ``overwrite``), holds other files, or cannot be created.
    """

    path: Path
    overwrite: bool = False
    failure: str | None = field(default=None, init=False)
    """Why the recording stopped early (a write failed, the writer process ended), or None."""
    topics: dict[str, _Topic] = field(default_factory=dict, init=False)

    def __post_init__(self) -> None:
        self.path = Path(self.path)
        prepare_directory(self.path, self.overwrite)
        self.file = self.path / f"{self.path.name}_0.mcap"
        self._closed = False
        self._committed: int | None = None
        self._queue: deque[tuple[int, int, bytes]] = deque()  # appended by the simulation thread, taken by any
        self._lock = threading.Lock()  # the pipe
        self._done = threading.Event()
        self._answered = threading.Event()
        try:
            self._proc = subprocess.Popen([sys.executable, "-P", _writer.__file__, str(self.path)],
                                          stdin=subprocess.PIPE, stdout=subprocess.PIPE, start_new_session=True)
        except OSError as e:
            raise BagError(f"cannot start the recording's writer process ({sys.executable}): {e.strerror or e}") \
                from None
        assert self._proc.stdin is not None and self._proc.stdout is not None
        self._pipe, answers = self._proc.stdin, self._proc.stdout
        with contextlib.suppress(OSError):  # a bigger pipe (Linux): the simulation rarely waits for the writer
            fcntl.fcntl(self._pipe.fileno(), getattr(fcntl, "F_SETPIPE_SZ", 1031), _PIPE_SIZE)
        first = _writer.read_frame(answers)
        if first is None or first[0] != "ready":
            self._proc.wait()
            why = first[1] if first is not None else f"it ended with exit code {self._proc.returncode}"
            raise BagError(f"the recording {self.path} cannot be written: {why}")
        self._listener = threading.Thread(target=self._listen, args=(answers,), name="sigcore-recorder-answers",
                                          daemon=True)
        self._listener.start()
        self._sender = threading.Thread(target=self._run, name="sigcore-recorder", daemon=True)
        self._sender.start()

    # ------------------------------------------------------------------ writing
    @property
    def messages(self) -> int:
        """Messages handed to the writer so far; after :meth:`close`, the messages the file holds."""
        if self._committed is not None:
            return self._committed
        return sum(t.count for t in self.topics.values())

    @property
    def active(self) -> bool:
        """Whether messages are still written (not closed, no failure)."""
        return not self._closed and self.failure is None

    def add_topic(self, name: str, typename: str, definition: str, digest: str, offered: Offered) -> _Topic | None:
        """Register topic ``name`` of ``typename`` (its ``ros2msg`` definition and RIHS01 hash), offered with
        ``offered``; the existing one if it is registered; None once the recording has stopped."""
        topic = self.topics.get(name)
        if topic is not None or not self.active:
            return topic
        topic = _Topic(name, len(self.topics))
        if not self._send(("topic", topic.channel, name, typename, definition.encode(), digest,
                           (offered.depth, offered.reliable, offered.latched))):
            return None
        self.topics[name] = topic
        return topic

    def write(self, topic: _Topic, stamp_ns: int, data: bytes) -> None:
        """Queue one serialized message of ``topic``, logged at ``stamp_ns`` (simulated time). The sending thread
        hands it to the writer process (or this call, when :data:`MAX_QUEUED` messages wait)."""
        if self.failure is not None or self._closed:
            return
        queue = self._queue
        queue.append((topic.channel, stamp_ns, data))
        topic.count += 1
        if len(queue) > MAX_QUEUED:
            self._flush()

    def attach(self, name: str, media_type: str, data: bytes, stamp_ns: int = 0) -> None:
        """Attach a file (``name``, e.g. ``world/cleanup.xml``) to the recording."""
        if self.active:
            self._send(("attach", name, media_type, bytes(data), stamp_ns))

    def metadata(self, name: str, values: dict[str, str]) -> None:
        """Add an MCAP metadata record ``name`` of string pairs."""
        if self.active:
            self._send(("metadata", name, dict(values)))

    def close(self, custom: dict[str, str] | None = None) -> None:
        """Hand over what is queued, then have the writer finish the MCAP file (its summary and indexes; after a
        failure, what was written whole) and write ``metadata.yaml``; wait for it. Idempotent."""
        if self._closed:
            return
        self._done.set()
        self._sender.join()
        self._flush()
        self._closed = True
        self._send(("close", dict(custom or {})))
        with contextlib.suppress(OSError):
            self._pipe.close()
        if not self._answered.wait(CLOSE_TIMEOUT):
            self._proc.kill()
            self._gone(f"the recording's writer process did not finish {self.file} within {CLOSE_TIMEOUT:.0f} s")
        try:
            self._proc.wait(CLOSE_TIMEOUT)
        except subprocess.TimeoutExpired:
            self._proc.kill()
        self._listener.join(5.0)
        if self._committed is None:  # the writer ended without saying what it holds
            self._committed = 0

    # ------------------------------------------------------------------ the writer process
    def _run(self) -> None:
        """The sending thread: every :data:`WRITE_PERIOD` seconds, hand what is queued to the writer."""
        while not self._done.wait(WRITE_PERIOD):
            if self._queue:
                self._flush()

    def _flush(self) -> None:
        """Hand every queued message to the writer process (any thread)."""
        with self._lock:
            self._put_queued()

    def _send(self, item: tuple[Any, ...]) -> bool:
        """Send one operation (after what is queued, which may refer to it); False if the writer has gone."""
        with self._lock:
            self._put_queued()
            return self._put(item)

    def _put_queued(self) -> None:
        """Send what is queued (under the lock; each ``popleft`` is atomic, so the simulation thread may append
        meanwhile)."""
        queue = self._queue
        batch = [queue.popleft() for _ in range(len(queue))]
        if batch and self.failure is None:
            self._put(("messages", batch))

    def _put(self, item: tuple[Any, ...]) -> bool:
        """Write one operation into the pipe (under the lock)."""
        try:
            self._pipe.write(_writer.frame(item))
            self._pipe.flush()
            return True
        except (OSError, ValueError):
            self._gone("the recording's writer process ended unexpectedly "
                       f"(exit code {self._proc.poll()}); the recording stopped there (the run goes on)")
            return False

    def _listen(self, answers: Any) -> None:
        """The writer's answers: a failure as soon as it happens, the counts at the close."""
        while True:
            item = _writer.read_frame(answers)
            if item is None:
                break
            if item[0] == "failed" and self.failure is None:
                self.failure = item[1]
                log.error("recording: %s", self.failure)
            elif item[0] == "closed":
                if item[1] and self.failure is None:
                    self.failure = item[1]
                    log.error("recording: %s", self.failure)
                self._committed = int(item[3])
                self._answered.set()
        self._answered.set()

    def _gone(self, why: str) -> None:
        if self.failure is None:
            self.failure = why
            log.error("recording %s: %s", self.path, why)


def prepare_directory(path: Path, overwrite: bool) -> None:
    """Make sure ``path`` can become a bag: it must not exist, or (with ``overwrite``) hold only a bag's files,
    which are removed.

    Raises:
        BagError: it exists (naming ``--overwrite``), holds other files, or is not a directory.
    """
    if path.exists() or path.is_symlink():
        if not overwrite:
            raise BagError(f"{path} exists already; choose another directory or add --overwrite to replace the "
                           "recording in it")
        if not path.is_dir():
            raise BagError(f"{path} exists and is not a directory: --overwrite only replaces a recording")
        others = sorted(p.name for p in path.iterdir() if p.name not in BAG_FILES and p.suffix != ".mcap"
                        and p.name != "metadata.yaml.tmp")
        if others:
            raise BagError(f"{path} holds files a recording does not ({', '.join(others[:5])}"
                           f"{', ...' if len(others) > 5 else ''}); --overwrite only replaces a recording: choose "
                           "another directory")
        shutil.rmtree(path)
    try:
        path.mkdir(parents=True)
    except OSError as e:
        raise BagError(f"cannot create the recording's directory {path}: {e.strerror or e}") from None
