"""The process that writes a recording: one MCAP file and its ``metadata.yaml`` (rosbag2 version 9).

:class:`sigcore.record.bag.BagWriter` starts it (``python -P _writer.py BAG_DIR``) and sends it, over its standard
input, length-prefixed pickled operations: topics, batches of serialized messages, attachments, metadata records
and the close. Building MCAP chunks and compressing them then runs on the machine's other core, not in the
simulation's interpreter (measured: in a thread of the simulation's process the writing cost about 5 % of the
simulation's speed; ``docs/benchmarks.md``). The process imports nothing of sigcore (so it starts fast), and
is in a session of its own (a Ctrl-C in the terminal goes to the run, which closes the recording).

Its answers go back over its standard output, pickled the same way: ``("ready",)`` or ``("error", text)`` at the
start, ``("failed", text)`` as soon as a write fails, and ``("closed", failure, counts, messages)`` at the end.

A write that fails (a full disk, a file size limit) stops the recording, never the run: the MCAP file is cut back to
the last record written whole and closed there (a data end and a footer, no summary section: readers scan it), and
``metadata.yaml`` counts what the file holds. When its input ends without a close (the run was killed), the process
closes the recording with what it received.
"""

from __future__ import annotations

import os
import pickle
import struct
import sys
import time
from pathlib import Path
from typing import IO, Any

COMPRESSION = "ZSTD"
"""How MCAP chunks are compressed (``ZSTD``, ``LZ4`` or ``NONE``; measured: the choice changes the run's speed by
less than this machine's noise, zstd makes the smallest files)."""
CHUNK_SIZE = 256 * 1024
"""Bytes of messages per MCAP chunk (a failure loses at most the chunk being written)."""
MAGIC = b"\x89MCAP0\r\n"

_INFINITE = {"sec": 9223372036, "nsec": 854775807}
"""rosbag2's infinite duration (deadline, lifespan, liveliness lease)."""
_LENGTH = struct.Struct("<I")


def qos_profiles(depth: int, reliable: bool, latched: bool) -> list[dict[str, Any]]:
    """rosbag2's ``offered_qos_profiles`` (version 9) of one publisher offering keep last ``depth``."""
    return [{"history": "keep_last", "depth": depth,
             "reliability": "reliable" if reliable else "best_effort",
             "durability": "transient_local" if latched else "volatile",
             "deadline": dict(_INFINITE), "lifespan": dict(_INFINITE), "liveliness": "automatic",
             "liveliness_lease_duration": dict(_INFINITE), "avoid_ros_namespace_conventions": False}]


def data_end_and_footer() -> bytes:
    """An MCAP data end record, a footer with no summary section, and the closing magic."""
    data_end = struct.pack("<BQI", 0x0F, 4, 0)
    footer = struct.pack("<BQQQI", 0x02, 20, 0, 0, 0)
    return data_end + footer + MAGIC


def frame(item: Any) -> bytes:
    """One operation or answer as it goes through a pipe: its length, then its pickle."""
    data = pickle.dumps(item, protocol=pickle.HIGHEST_PROTOCOL)
    return _LENGTH.pack(len(data)) + data


def read_frame(stream: IO[bytes]) -> Any:
    """The next operation or answer from ``stream``; None at its end."""
    head = stream.read(4)
    if len(head) < 4:
        return None
    (n,) = _LENGTH.unpack(head)
    data = stream.read(n)
    if len(data) < n:
        return None
    return pickle.loads(data)


class _Stream:
    """The MCAP file, unbuffered: :attr:`good` is the end of the last write that completed (writes are whole
    records), where the file is cut if a later write fails."""

    def __init__(self, path: Path) -> None:
        self.file = open(path, "xb", buffering=0)  # noqa: SIM115 - closed by _Bag
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


class _Bag:
    """The recording being written: the MCAP writer, each topic's count, what is committed to the file."""

    def __init__(self, path: Path, report: Any) -> None:
        from mcap.writer import CompressionType, Writer

        self.path = path
        self.file = path / f"{path.name}_0.mcap"
        self.report = report
        self.stream = _Stream(self.file)
        self.writer = Writer(self.stream, chunk_size=CHUNK_SIZE,  # type: ignore[arg-type]
                             compression=getattr(CompressionType, COMPRESSION))  # type: ignore[arg-type]
        self.schemas: dict[str, int] = {}
        self.topics: list[dict[str, Any]] = []  # by the parent's index: name, type, digest, qos, channel, count
        self.committed: list[int] = []  # per topic: messages in the file for certain
        self.start: int | None = None
        self.end = 0
        self.failure: str | None = None
        self.guard(lambda: self.writer.start(profile="ros2", library="sigcore"))

    # ------------------------------------------------------------------ operations
    def topic(self, index: int, name: str, typename: str, definition: bytes, digest: str,
              offered: tuple[int, bool, bool]) -> None:
        import yaml

        qos = qos_profiles(*offered)
        topic = {"name": name, "type": typename, "digest": digest, "qos": qos, "channel": -1, "count": 0}
        while len(self.topics) <= index:
            self.topics.append({})
            self.committed.append(0)
        self.topics[index] = topic

        def register() -> None:
            schema = self.schemas.get(typename)
            if schema is None:
                schema = self.schemas[typename] = self.writer.register_schema(typename, "ros2msg", definition)
            topic["channel"] = self.writer.register_channel(
                name, "cdr", schema, {"offered_qos_profiles": yaml.safe_dump(qos, sort_keys=False).strip(),
                                      "topic_type_hash": digest})

        self.guard(register)

    def messages(self, batch: list[tuple[int, int, bytes]]) -> None:
        writer, stream, topics = self.writer, self.stream, self.topics
        for index, stamp_ns, data in batch:
            if self.failure is not None:
                return
            topic = topics[index]
            before = stream.writes
            try:
                writer.add_message(topic["channel"], stamp_ns, data, stamp_ns)
            except OSError as e:
                self.fail(e)
                return
            topic["count"] += 1
            if self.start is None or stamp_ns < self.start:
                self.start = stamp_ns
            if stamp_ns > self.end:
                self.end = stamp_ns
            if stream.writes != before:  # a chunk went to the file: every message so far is in it
                self.committed = [t.get("count", 0) for t in topics]

    def attach(self, name: str, media_type: str, data: bytes, stamp_ns: int) -> None:
        self.guard(lambda: self.writer.add_attachment(time.time_ns(), stamp_ns, name, media_type, data))

    def metadata(self, name: str, values: dict[str, str]) -> None:
        self.guard(lambda: self.writer.add_metadata(name, values))

    def close(self, custom: dict[str, str] | None) -> None:
        """Finish the MCAP file (its summary and indexes; after a failure, what was written whole) and write
        ``metadata.yaml``."""
        if self.failure is None:
            try:
                self.writer.finish()
                self.committed = [t.get("count", 0) for t in self.topics]
            except OSError as e:
                self.fail(e)
        try:
            self.stream.file.close()
        except OSError as e:
            self.fail(e)
        try:
            self.write_metadata(custom or {})
        except OSError as e:
            self.failure = self.failure or f"cannot write {self.path / 'metadata.yaml'}: {e.strerror or e}"

    # ------------------------------------------------------------------ failures
    def guard(self, action: Any) -> Any:
        if self.failure is not None:
            return None
        try:
            return action()
        except OSError as e:
            self.fail(e)
            return None

    def fail(self, error: OSError) -> None:
        """A write failed: stop recording, cut the file back to its last whole record and close it there."""
        if self.failure is not None:
            return
        what = error.strerror or str(error)
        self.failure = (f"writing {self.file} failed at byte {self.stream.pos}: {what}; the recording stopped "
                        f"there (the run goes on) and keeps the {sum(self.committed)} messages written before")
        try:
            f = self.stream.file
            f.truncate(self.stream.good)
            os.lseek(f.fileno(), self.stream.good, os.SEEK_SET)
            f.write(data_end_and_footer())
        except OSError as e:
            self.failure += (f"; the file cannot be closed cleanly ({e.strerror or e}): sigcore bag info still reads "
                             "what it holds")
        self.report(("failed", self.failure))

    def write_metadata(self, custom: dict[str, str]) -> None:
        """``metadata.yaml`` (rosbag2 version 9) for what the MCAP file holds."""
        import yaml

        pairs = [(t, n) for t, n in zip(self.topics, self.committed, strict=True) if t]
        start = self.start or 0
        duration = max(0, self.end - start)
        total = sum(n for _, n in pairs)
        info = {
            "version": 9, "storage_identifier": "mcap", "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start}, "message_count": total,
            "topics_with_message_count": [
                {"topic_metadata": {"name": t["name"], "type": t["type"], "serialization_format": "cdr",
                                    "offered_qos_profiles": t["qos"], "type_description_hash": t["digest"]},
                 "message_count": n} for t, n in pairs],
            "compression_format": "", "compression_mode": "",
            "relative_file_paths": [self.file.name],
            "files": [{"path": self.file.name, "starting_time": {"nanoseconds_since_epoch": start},
                       "duration": {"nanoseconds": duration}, "message_count": total}],
            "custom_data": custom or None, "ros_distro": "jazzy",
        }
        tmp = self.path / "metadata.yaml.tmp"
        tmp.write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}, sort_keys=False))
        tmp.replace(self.path / "metadata.yaml")


def main(argv: list[str]) -> int:
    """Write the recording in directory ``argv[1]`` (it exists, empty) from the operations on standard input."""
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer

    def report(item: Any) -> None:
        try:
            stdout.write(frame(item))
            stdout.flush()
        except (BrokenPipeError, OSError):
            pass  # the run has gone: the recording is closed all the same

    path = Path(argv[1])
    try:
        bag = _Bag(path, report)
    except OSError as e:
        report(("error", f"cannot create {path / (path.name + '_0.mcap')}: {e.strerror or e}"))
        return 1
    except ImportError as e:
        report(("error", f"the recording's writer cannot start: {e}; install the mcap package"))
        return 1
    report(("ready",))
    custom: dict[str, str] | None = None
    while True:
        op = read_frame(stdin)
        if op is None or op[0] == "close":
            custom = op[1] if op is not None else None
            break
        kind = op[0]
        if kind == "messages":
            bag.messages(op[1])
        elif kind == "topic":
            bag.topic(*op[1:])
        elif kind == "attach":
            bag.attach(*op[1:])
        elif kind == "metadata":
            bag.metadata(*op[1:])
    bag.close(custom)
    report(("closed", bag.failure, bag.committed, sum(bag.committed)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
