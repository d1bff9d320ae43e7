"""rosbag2 directories with MCAP storage: written by :class:`BagWriter`, checked and summarised by :func:`bag_info`.

A bag is a directory holding ``metadata.yaml`` (rosbag2 version 9, ROS 2 Jazzy: topics with their types, RIHS01
type hashes, offered QoS and message counts) and one MCAP file ``<dir>_0.mcap`` (profile ``ros2``, CDR messages,
``ros2msg`` schemas, zstd-compressed chunks, the offered QoS in each channel's metadata as rosbag2 writes it), so
``ros2 bag info``, ``ros2 bag play`` and Foxglove open it. Files that make a recording self-contained (the world file,
its URDFs) are MCAP attachments; facts about the run are an MCAP metadata record.

A write that fails (a full disk, a file size limit) stops the recording, never the run: the MCAP file is cut back to
the last record written whole and closed there (a data end and a footer, no summary section: readers scan it), and
``metadata.yaml`` counts what the file holds. The file is written by a process of its own
(:mod:`sigcore.record._writer`), which closes the recording when the run is killed. A recording whose writer was
killed before it ended has no ``metadata.yaml``; :func:`bag_info` says so and how many messages are readable.
"""

from __future__ import annotations

import contextlib
import fcntl
import logging
import shutil
import struct
import subprocess
import sys
import threading
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ..errors import SigcoreError
from ..publish import Offered
from . import _writer
from ._writer import MAGIC

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


class BagError(SigcoreError, ValueError):
    """A bag cannot be written (its directory exists, is not writable) or read (missing, cut, foreign)."""


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


# ---------------------------------------------------------------------- reading
@dataclass
class TopicInfo:
    """One topic of a bag: its type, count, offered QoS and whether it is latched."""

    name: str
    typename: str
    count: int
    latched: bool
    digest: str = ""
    offered: Offered = field(default_factory=lambda: Offered(10))
    """The QoS it was offered with (the first of its ``offered_qos_profiles``)."""


@dataclass
class BagInfo:
    """What :func:`bag_info` found in a bag."""

    path: Path
    files: list[Path]
    size: int
    start_ns: int
    end_ns: int
    topics: list[TopicInfo]
    attachments: list[tuple[str, str, int]]
    metadata: dict[str, dict[str, str]]
    problems: list[str]

    @property
    def messages(self) -> int:
        return sum(t.count for t in self.topics)


def bag_info(path: Path) -> BagInfo:
    """Read ``path`` (a bag directory, or one ``.mcap`` file) and check it: topics, counts, times, attachments.
    A bag cut short (killed while recording, a failed write) is read as far as it goes and its problems are listed.

    Raises:
        BagError: no such path, no MCAP file, or a file that is not MCAP (naming it and what is wrong).
    """
    path = Path(path)
    if not path.exists():
        raise BagError(f"{path}: no such file or directory")
    problems: list[str] = []
    declared: dict[str, Any] = {}
    if path.is_dir():
        meta = path / "metadata.yaml"
        if meta.exists():
            try:
                declared = (yaml.safe_load(meta.read_text()) or {}).get("rosbag2_bagfile_information") or {}
            except (yaml.YAMLError, AttributeError, UnicodeDecodeError) as e:
                problems.append(f"{meta} is not rosbag2 metadata ({type(e).__name__}: {str(e).splitlines()[0]})")
            files = [path / rel for rel in declared.get("relative_file_paths") or []]
            missing = [str(f) for f in files if not f.exists()]
            if missing:
                raise BagError(f"{meta} names {', '.join(missing)}, which {'is' if len(missing) == 1 else 'are'} "
                               "missing")
        else:
            problems.append(f"{meta} is missing: the recording did not end normally (killed?); what the MCAP "
                            "file holds is listed")
            files = []
        if not files:
            files = sorted(path.glob("*.mcap"))
        if not files:
            raise BagError(f"{path} holds no .mcap file: not a rosbag2 recording with MCAP storage")
    else:
        files = [path]
    topics: dict[str, TopicInfo] = {}
    attachments: list[tuple[str, str, int]] = []
    metadata: dict[str, dict[str, str]] = {}
    start, end = 2**63 - 1, 0
    for file in files:
        first, last = _scan(file, topics, attachments, metadata, problems)
        start, end = min(start, first), max(end, last)
    if declared:
        for entry in declared.get("topics_with_message_count") or []:
            name = (entry.get("topic_metadata") or {}).get("name")
            if name in topics and entry.get("message_count") != topics[name].count:
                problems.append(f"metadata.yaml counts {entry.get('message_count')} messages on {name}, the MCAP "
                                f"file holds {topics[name].count}")
    if start > end:
        start = end = 0
    return BagInfo(path, files, sum(f.stat().st_size for f in files), start, end, list(topics.values()),
                   attachments, metadata, problems)


def _scan(file: Path, topics: dict[str, TopicInfo], attachments: list[tuple[str, str, int]],
          metadata: dict[str, dict[str, str]], problems: list[str]) -> tuple[int, int]:
    """Read every record of one MCAP file (through its chunks), up to where it is cut."""
    from mcap.exceptions import McapError
    from mcap.records import Attachment, Channel, Footer, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader

    channels: dict[int, TopicInfo] = {}
    schemas: dict[int, str] = {}
    start, end = 2**63 - 1, 0
    footer = False
    with open(file, "rb") as f:
        head = f.read(len(MAGIC))
        if head != MAGIC:
            raise BagError(f"{file} is not an MCAP file (it starts with {head[:8]!r}, not the MCAP magic)")
        f.seek(0)
        try:
            for record in StreamReader(f, emit_chunks=False, validate_crcs=True).records:  # type: ignore[arg-type]
                if isinstance(record, Schema):
                    schemas[record.id] = record.name
                elif isinstance(record, Channel):
                    offered = _offered(record.metadata.get("offered_qos_profiles", ""))
                    info = topics.setdefault(record.topic, TopicInfo(record.topic, schemas.get(record.schema_id, "?"),
                                                                     0, offered.latched,
                                                                     record.metadata.get("topic_type_hash", ""),
                                                                     offered))
                    channels[record.id] = info
                elif isinstance(record, Message):
                    of = channels.get(record.channel_id)
                    if of is None:
                        raise BagError(f"{file}: a message on channel {record.channel_id}, which no channel record "
                                       "declares: not a recording sigcore or rosbag2 can read")
                    of.count += 1
                    start, end = min(start, record.log_time), max(end, record.log_time)
                elif isinstance(record, Attachment):
                    attachments.append((record.name, record.media_type, len(record.data)))
                elif isinstance(record, Metadata):
                    metadata[record.name] = dict(record.metadata)
                elif isinstance(record, Footer):
                    footer = True
        except (McapError, EOFError, struct.error, ValueError, OSError) as e:
            if isinstance(e, BagError):
                raise
            size = file.stat().st_size
            problems.append(f"{file} is cut or damaged ({type(e).__name__}: {str(e) or 'ends inside a record'}; "
                            f"{size} bytes): the messages before that point are listed")
            return start, end
    if not footer:
        problems.append(f"{file} ends without an MCAP footer: the recording did not end normally")
    return start, end


def read_extras(info: BagInfo) -> tuple[dict[str, dict[str, str]], dict[str, bytes]]:
    """The MCAP metadata records (by name) and the attachments (name -> bytes) of a bag :func:`bag_info` read; of a
    file cut short, those before the cut."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap.records import Attachment, Metadata
    from mcap.stream_reader import StreamReader

    metadata: dict[str, dict[str, str]] = {}
    attachments: dict[str, bytes] = {}
    for file in info.files:
        with open(file, "rb") as f:
            if not info.problems:  # a whole file: through its summary's indexes
                reader = make_reader(f)
                for meta in reader.iter_metadata():
                    metadata.setdefault(meta.name, {}).update(meta.metadata)
                for attachment in reader.iter_attachments():
                    attachments[attachment.name] = attachment.data
                continue
            try:  # a cut file: every record up to the cut (chunks not decompressed)
                for record in StreamReader(f, emit_chunks=True).records:  # type: ignore[arg-type]
                    if isinstance(record, Metadata):
                        metadata.setdefault(record.name, {}).update(record.metadata)
                    elif isinstance(record, Attachment):
                        attachments[record.name] = record.data
            except (McapError, EOFError, struct.error, ValueError, OSError):
                pass
    return metadata, attachments


def _offered(text: str) -> Offered:
    """The first profile of a channel's ``offered_qos_profiles`` (rosbag2's YAML), as :class:`Offered`; reliable,
    volatile, depth 10 when it says nothing readable."""
    try:
        profiles = yaml.safe_load(text) if text else None
        first = profiles[0] if isinstance(profiles, list) and profiles and isinstance(profiles[0], dict) else {}
    except yaml.YAMLError:
        first = {}
    depth = first.get("depth", 10)
    reliability, durability = str(first.get("reliability", "reliable")), str(first.get("durability", "volatile"))
    return Offered(depth if isinstance(depth, int) and depth > 0 else 10,
                   reliability not in ("best_effort", "2"), durability in ("transient_local", "1"))


def iter_messages(info: BagInfo, topics: Iterable[str] | None = None) -> Iterator[tuple[str, int, bytes]]:
    """``(topic, log time [ns], serialized data)`` of every message of a bag :func:`bag_info` read, in log-time
    order (a bag cut short: in file order, up to where it is cut), only of ``topics`` if given."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    wanted = None if topics is None else set(topics)
    for file in info.files:
        with open(file, "rb") as f:
            if not info.problems:
                for _, channel, message in make_reader(f).iter_messages(topics=wanted, log_time_order=True):
                    yield channel.topic, message.log_time, message.data
                continue
            names: dict[int, str] = {}
            try:
                for record in StreamReader(f, emit_chunks=False).records:  # type: ignore[arg-type]
                    if isinstance(record, Channel):
                        names[record.id] = record.topic
                    elif isinstance(record, Message):
                        topic = names.get(record.channel_id, "")
                        if wanted is None or topic in wanted:
                            yield topic, record.log_time, record.data
            except (McapError, EOFError, struct.error, ValueError, OSError):
                return


def format_info(info: BagInfo) -> Iterable[str]:
    """Lines like ``ros2 bag info`` prints, then the attachments, the run's metadata and any problems."""
    duration = (info.end_ns - info.start_ns) / 1e9
    yield f"Files:             {', '.join(str(f) for f in info.files)}"
    yield f"Bag size:          {_size(info.size)}"
    yield "Storage id:        mcap"
    yield f"Duration:          {duration:.3f}s"
    yield f"Start:             {info.start_ns / 1e9:.3f} (simulated time, s)"
    yield f"End:               {info.end_ns / 1e9:.3f} (simulated time, s)"
    yield f"Messages:          {info.messages}"
    width = max((len(t.name) for t in info.topics), default=0)
    for i, t in enumerate(sorted(info.topics, key=lambda t: t.name)):
        label = "Topic information: " if i == 0 else " " * 19
        yield (f"{label}Topic: {t.name:<{width}} | Type: {t.typename} | Count: {t.count} | Serialization "
               f"Format: cdr{' | latched' if t.latched else ''}")
    for name, media, size in info.attachments:
        yield f"Attachment:        {name} ({media}, {_size(size)})"
    for name, values in info.metadata.items():
        yield f"Metadata {name}: " + ", ".join(f"{k}={v}" for k, v in values.items())
    for p in info.problems:
        yield f"Problem:           {p}"


def _size(n: int) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{n} B"
        n /= 1024  # type: ignore[assignment]
    return f"{n} B"
