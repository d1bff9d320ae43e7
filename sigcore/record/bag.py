"""rosbag2 directories with MCAP storage: written by :class:`BagWriter`, checked and summarised by :func:`bag_info`.

A bag is a directory holding ``metadata.yaml`` (rosbag2 version 9, ROS 2 Jazzy: topics with their types, RIHS01
type hashes, offered QoS and message counts) and one MCAP file ``<dir>_0.mcap`` (profile ``ros2``, CDR messages,
``ros2msg`` schemas, zstd-compressed chunks, the offered QoS in each channel's metadata as rosbag2 writes it), so
``ros2 bag info``, ``ros2 bag play`` and Foxglove open it. Files that make a recording self-contained (the world file,
its URDFs) are MCAP attachments; facts about the run are an MCAP metadata record.

A write that fails (a full disk, a file size limit) stops the recording, never the run: the MCAP file is cut back to
the last record written whole and closed there (a data end and a footer, no summary section: readers scan it), and
``metadata.yaml`` counts what the file holds. A recording killed before it ended has no ``metadata.yaml``;
:func:`bag_info` says so and how many messages are readable.
"""

from __future__ import annotations

import logging
import os
import shutil
import struct
import threading
import time
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ..errors import SigcoreError
from ..publish import Offered

log = logging.getLogger("sigcore.record")

MAX_QUEUED = 20_000
"""Messages that may wait for the writing thread; beyond, the simulation thread writes them itself."""
WRITE_PERIOD = 0.05
"""How often the writing thread writes what is queued [s of wall time]."""
COMPRESSION = "ZSTD"
"""How MCAP chunks are compressed (``ZSTD``, ``LZ4`` or ``NONE``; measured: the choice changes the run's speed by
less than this machine's noise, zstd makes the smallest files)."""
CHUNK_SIZE = 256 * 1024
"""Bytes of messages per MCAP chunk (a failure loses at most the chunk being written)."""

_INFINITE = {"sec": 9223372036, "nsec": 854775807}
"""rosbag2's infinite duration (deadline, lifespan, liveliness lease)."""

MAGIC = b"\x89MCAP0\r\n"
BAG_FILES = ("metadata.yaml",)
"""Besides ``*.mcap``, what a bag directory holds (``--overwrite`` removes a directory with nothing else)."""


class BagError(SigcoreError, ValueError):
    """A bag cannot be written (its directory exists, is not writable) or read (missing, cut, foreign)."""


def qos_profiles(offered: Offered) -> list[dict[str, Any]]:
    """rosbag2's ``offered_qos_profiles`` (version 9) of one publisher offering ``offered``."""
    return [{"history": "keep_last", "depth": offered.depth,
             "reliability": "reliable" if offered.reliable else "best_effort",
             "durability": "transient_local" if offered.latched else "volatile",
             "deadline": dict(_INFINITE), "lifespan": dict(_INFINITE), "liveliness": "automatic",
             "liveliness_lease_duration": dict(_INFINITE), "avoid_ros_namespace_conventions": False}]


class _Stream:
    """The MCAP file, unbuffered: :attr:`good` is the end of the last write that completed (writes are whole
    records), where the file is cut if a later write fails."""

    def __init__(self, path: Path) -> None:
        self.file = open(path, "xb", buffering=0)  # noqa: SIM115 - closed by BagWriter
        self.pos = 0
        self.good = 0
        self.writes = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        view = memoryview(data)
        while view:
            n = self.file.write(view)
            if not n:
                raise OSError(f"no byte written at offset {self.pos}")
            self.pos += n
            view = view[n:]
        self.good = self.pos
        self.writes += 1
        return len(data)

    def tell(self) -> int:
        return self.pos

    def flush(self) -> None:
        pass


@dataclass
class _Topic:
    name: str
    typename: str
    digest: str
    offered: Offered
    channel: int
    count: int = 0


@dataclass
class BagWriter:
    """Writes one rosbag2 directory (MCAP storage).

    Args:
        path: The directory to create.
        overwrite: Replace ``path`` if it exists and holds a bag (``metadata.yaml`` and ``.mcap`` files only).

    Raises:
        BagError: ``path`` exists (without ``overwrite``), holds other files, or cannot be created.
    """

    path: Path
    overwrite: bool = False
    failure: str | None = field(default=None, init=False)
    """Why the recording stopped early (a write failed), or None."""
    topics: dict[str, _Topic] = field(default_factory=dict, init=False)

    def __post_init__(self) -> None:
        from mcap.writer import CompressionType, Writer

        self.path = Path(self.path)
        prepare_directory(self.path, self.overwrite)
        self.file = self.path / f"{self.path.name}_0.mcap"
        try:
            self._stream = _Stream(self.file)
        except OSError as e:
            raise BagError(f"cannot create {self.file}: {e.strerror or e}") from None
        self._writer = Writer(self._stream, chunk_size=CHUNK_SIZE,  # type: ignore[arg-type]
                              compression=getattr(CompressionType, COMPRESSION))  # type: ignore[arg-type]
        self._schemas: dict[str, int] = {}
        self._committed: dict[str, int] = {}
        self._start: int | None = None
        self._end = 0
        self._closed = False
        self._guard(lambda: self._writer.start(profile="ros2", library="sigcore"))
        # messages are queued by the simulation thread and written by a thread of their own, which runs while the
        # simulation thread is in the physics engine (MuJoCo releases the interpreter there); the lock guards the
        # MCAP writer and the counts
        self._queue: deque[tuple[_Topic, int, bytes]] = deque()
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, name="sigcore-recorder", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ writing
    @property
    def messages(self) -> int:
        """Messages written so far (those still queued not counted)."""
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
        writer = self._writer

        def register() -> int:  # under the lock (the writing thread uses the MCAP writer too)
            schema = self._schemas.get(typename)
            if schema is None:
                schema = self._schemas[typename] = writer.register_schema(typename, "ros2msg", definition.encode())
            qos = yaml.safe_dump(qos_profiles(offered), sort_keys=False).strip()
            return writer.register_channel(name, "cdr", schema, {"offered_qos_profiles": qos,
                                                                 "topic_type_hash": digest})

        with self._lock:
            channel = self._guard(register)
        if channel is None:
            return None
        topic = self.topics[name] = _Topic(name, typename, digest, offered, channel)
        return topic

    def write(self, topic: _Topic, stamp_ns: int, data: bytes) -> None:
        """Queue one serialized message of ``topic``, logged at ``stamp_ns`` (simulated time); the writing thread
        writes it (or this call, when :data:`MAX_QUEUED` messages wait: the simulation then waits for the disk)."""
        if self.failure is not None or self._closed:
            return
        queue = self._queue
        queue.append((topic, stamp_ns, data))
        if len(queue) > MAX_QUEUED:
            self._drain()

    def _run(self) -> None:
        """The writing thread: every :data:`WRITE_PERIOD` seconds, write what is queued."""
        while not self._done.wait(WRITE_PERIOD):
            if self._queue:
                self._drain()

    def _drain(self) -> None:
        """Write every queued message (any thread; one at a time)."""
        with self._lock:
            queue, writer, stream = self._queue, self._writer, self._stream
            while queue and self.failure is None:
                topic, stamp_ns, data = queue.popleft()
                before = stream.writes
                try:
                    writer.add_message(topic.channel, stamp_ns, data, stamp_ns)
                except OSError as e:
                    self._fail(e)
                    break
                topic.count += 1
                if self._start is None or stamp_ns < self._start:
                    self._start = stamp_ns
                if stamp_ns > self._end:
                    self._end = stamp_ns
                if stream.writes != before:  # a chunk went to the file: every message so far is in it
                    self._committed = {t.name: t.count for t in self.topics.values()}
            if self.failure is not None:
                queue.clear()

    def attach(self, name: str, media_type: str, data: bytes, stamp_ns: int = 0) -> None:
        """Attach a file (``name``, e.g. ``world/cleanup.xml``) to the recording."""
        if self.active:
            with self._lock:
                self._guard(lambda: self._writer.add_attachment(time.time_ns(), stamp_ns, name, media_type, data))

    def metadata(self, name: str, values: dict[str, str]) -> None:
        """Add an MCAP metadata record ``name`` of string pairs."""
        if self.active:
            with self._lock:
                self._guard(lambda: self._writer.add_metadata(name, values))

    def close(self, custom: dict[str, str] | None = None) -> None:
        """Finish the MCAP file (its summary and indexes) and write ``metadata.yaml``; after a failure, close what
        was written whole (see the module's docstring). Idempotent."""
        if self._closed:
            return
        self._done.set()
        self._thread.join()
        self._drain()
        if self.failure is None:
            try:
                self._writer.finish()
                self._committed = {t.name: t.count for t in self.topics.values()}
            except OSError as e:
                self._fail(e)
        self._closed = True
        try:
            self._stream.file.close()
        except OSError as e:
            self._fail(e)
        try:
            self._write_metadata(custom or {})
        except OSError as e:
            self.failure = self.failure or f"cannot write {self.path / 'metadata.yaml'}: {e.strerror or e}"
            log.error("recording %s: %s", self.path, self.failure)

    # ------------------------------------------------------------------ failures
    def _guard(self, action: Any) -> Any:
        try:
            return action()
        except OSError as e:
            self._fail(e)
            return None

    def _fail(self, error: OSError) -> None:
        """A write failed: stop recording, cut the file back to its last whole record and close it there."""
        if self.failure is not None:
            return
        what = error.strerror or str(error)
        self.failure = (f"writing {self.file} failed at byte {self._stream.pos}: {what}; the recording stopped "
                        f"there (the run goes on) and keeps the {sum(self._committed.values())} messages written "
                        "before")
        log.error("recording: %s", self.failure)
        try:
            f = self._stream.file
            f.truncate(self._stream.good)
            os.lseek(f.fileno(), self._stream.good, os.SEEK_SET)
            f.write(_data_end_and_footer())
        except OSError as e:
            log.error("recording: %s cannot be closed cleanly (%s); bag info still reads what it holds", self.file,
                      e.strerror or e)

    def _write_metadata(self, custom: dict[str, str]) -> None:
        """``metadata.yaml`` (rosbag2 version 9) for what the MCAP file holds."""
        counts = self._committed
        start = self._start or 0
        duration = max(0, self._end - start)
        total = sum(counts.get(t.name, 0) for t in self.topics.values())
        info = {
            "version": 9, "storage_identifier": "mcap", "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start}, "message_count": total,
            "topics_with_message_count": [
                {"topic_metadata": {"name": t.name, "type": t.typename, "serialization_format": "cdr",
                                    "offered_qos_profiles": qos_profiles(t.offered),
                                    "type_description_hash": t.digest},
                 "message_count": counts.get(t.name, 0)} for t in self.topics.values()],
            "compression_format": "", "compression_mode": "",
            "relative_file_paths": [self.file.name],
            "files": [{"path": self.file.name, "starting_time": {"nanoseconds_since_epoch": start},
                       "duration": {"nanoseconds": duration}, "message_count": total}],
            "custom_data": custom or None, "ros_distro": "jazzy",
        }
        tmp = self.path / "metadata.yaml.tmp"
        tmp.write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}, sort_keys=False))
        tmp.replace(self.path / "metadata.yaml")


def _data_end_and_footer() -> bytes:
    """An MCAP data end record, a footer with no summary section, and the closing magic."""
    data_end = struct.pack("<BQI", 0x0F, 4, 0)
    footer = struct.pack("<BQQQI", 0x02, 20, 0, 0, 0)
    return data_end + footer + MAGIC


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
