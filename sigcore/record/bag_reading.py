"""Reading rosbag2 directories with MCAP storage (any bag, not only sigcore's): :func:`bag_info` checks and summarises
one, :func:`read_extras` gives its metadata records and attachments, :func:`iter_messages` its messages, in log-time
or written order; a bag cut short is read as far as it goes. What a *sigcore* recording means (its world, its input
log, its ground truth) is :mod:`sigcore.record.reader`'s.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ..publish import Offered
from ._writer import MAGIC
from .exceptions import BagError


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


def iter_messages(info: BagInfo, topics: Iterable[str] | None = None,
                  written_order: bool = False) -> Iterator[tuple[str, int, bytes]]:
    """``(topic, log time [ns], serialized data)`` of every message of a bag :func:`bag_info` read, in log-time
    order (``written_order``: in the order written; a bag cut short: in file order, up to where it is cut), only of
    ``topics`` if given."""
    from mcap.exceptions import McapError
    from mcap.reader import make_reader
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader

    wanted = None if topics is None else set(topics)
    for file in info.files:
        with open(file, "rb") as f:
            if not info.problems:
                for _, channel, message in make_reader(f).iter_messages(topics=wanted,
                                                                         log_time_order=not written_order):
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
