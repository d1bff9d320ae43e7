"""The link between the simulation's process and the viewer's process: messages over a Unix socket pair.

A message is a tuple whose first item names it (``("snap", snapshot)``, ``("play",)``...), sent as a 4-byte
length and a pickle. Both ends are sigcore's own processes, started by the same program from the same installation:
pickle is safe here (nothing from a browser is ever unpickled; the browser's input arrives as viser's callbacks in
the viewer's process and crosses as plain tuples of names and numbers).

The simulation's end never blocks: :class:`Outbox` keeps what the socket did not take and sends it at the next
call, and :class:`Inbox` reads only what has arrived.
"""

from __future__ import annotations

import pickle
import socket
import struct
from collections.abc import Iterator
from typing import Any

from .exceptions import PeerGone

HEADER = struct.Struct("<I")
LIMIT = 256 * 1024 * 1024
"""The largest message either end accepts [bytes] (a map or a camera image is far smaller)."""
BUFFER = 4 * 1024 * 1024
"""The socket buffers asked for [bytes]: room for a few snapshots with images."""


def encode(message: tuple[Any, ...]) -> bytes:
    """``message`` framed: its length, then its pickle."""
    body = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    return HEADER.pack(len(body)) + body


def tune(sock: socket.socket) -> None:
    """Ask for large buffers both ways (the kernel caps them at its limits; whatever it grants works)."""
    for option in (socket.SO_SNDBUF, socket.SO_RCVBUF):
        try:
            sock.setsockopt(socket.SOL_SOCKET, option, BUFFER)
        except OSError:
            pass


class Outbox:
    """Messages to the peer, sent without blocking: what the socket does not take now waits for :meth:`flush`.

    Args:
        sock: The non-blocking socket.
    """

    def __init__(self, sock: socket.socket) -> None:
        self._sock = sock
        self._pending = bytearray()

    @property
    def empty(self) -> bool:
        """Whether everything queued has been handed to the socket."""
        return not self._pending

    def put(self, message: tuple[Any, ...]) -> None:
        """Queue ``message`` and send what the socket takes now.

        Raises:
            PeerGone: the peer closed its end.
        """
        self._pending += encode(message)
        self.flush()

    def flush(self) -> bool:
        """Send what the socket takes now; returns whether nothing is left.

        Raises:
            PeerGone: the peer closed its end.
        """
        while self._pending:
            try:
                sent = self._sock.send(self._pending)
            except (BlockingIOError, InterruptedError):
                return False
            except OSError as e:  # EPIPE, ECONNRESET: the viewer's process is gone
                raise PeerGone(str(e)) from e
            del self._pending[:sent]
        return True


class Inbox:
    """Messages from the peer: :meth:`read` returns those complete so far, without blocking.

    Args:
        sock: The non-blocking socket.
    """

    def __init__(self, sock: socket.socket) -> None:
        self._sock = sock
        self._data = bytearray()
        self._closed = False

    def read(self) -> list[tuple[Any, ...]]:
        """Every complete message that has arrived (none: an empty list).

        Raises:
            PeerGone: the peer closed its end.
            ValueError: a message is larger than :data:`LIMIT` (the stream is not from a sigcore viewer).
        """
        if self._closed:
            raise PeerGone("the viewer's process closed its end")
        while True:
            try:
                chunk = self._sock.recv(1 << 20)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as e:
                raise PeerGone(str(e)) from e
            if not chunk:
                self._closed = True
                break
            self._data += chunk
        messages = list(_split(self._data))
        if self._closed and not messages:
            raise PeerGone("the viewer's process closed its end")
        return messages


def _split(data: bytearray) -> Iterator[tuple[Any, ...]]:
    """Take the complete messages off the front of ``data``."""
    while len(data) >= HEADER.size:
        (size,) = HEADER.unpack_from(data)
        if size > LIMIT:
            raise ValueError(f"a message of {size} bytes from the viewer's process (at most {LIMIT})")
        if len(data) < HEADER.size + size:
            return
        message = pickle.loads(bytes(data[HEADER.size:HEADER.size + size]))
        del data[:HEADER.size + size]
        yield message


def receive(sock: socket.socket) -> tuple[Any, ...]:
    """The next message on a blocking socket.

    Raises:
        PeerGone: the peer closed its end.
    """
    (size,) = HEADER.unpack(_exactly(sock, HEADER.size))
    if size > LIMIT:
        raise ValueError(f"a message of {size} bytes (at most {LIMIT})")
    message: tuple[Any, ...] = pickle.loads(_exactly(sock, size))
    return message


def _exactly(sock: socket.socket, size: int) -> bytes:
    out = bytearray()
    while len(out) < size:
        try:
            chunk = sock.recv(size - len(out))
        except OSError as e:
            raise PeerGone(str(e)) from e
        if not chunk:
            raise PeerGone("the simulation's process closed its end")
        out += chunk
    return bytes(out)
