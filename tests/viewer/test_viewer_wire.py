"""The link between the simulation's process and the viewer's process (sigcore_viewer.wire), on a real socket pair:
framing across partial reads, a full socket that never blocks the sender, a closed peer, a stream that is no
viewer's."""

from __future__ import annotations

import socket
import struct
from collections.abc import Iterator

import numpy as np
import pytest
from sigcore_viewer import wire


@pytest.fixture
def pair() -> Iterator[tuple[socket.socket, socket.socket]]:
    a, b = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
    a.setblocking(False)
    b.setblocking(False)
    try:
        yield a, b
    finally:
        a.close()
        b.close()


def test_a_message_split_anywhere_arrives_whole(pair: tuple[socket.socket, socket.socket]) -> None:
    """Two messages sent byte-range by byte-range arrive whole, in order, once both are complete; arrays survive."""
    a, b = pair
    inbox = wire.Inbox(b)
    first, second = ("snap", np.arange(6.0).reshape(2, 3)), ("selected", "can_0", None)
    data = wire.encode(first) + wire.encode(second)
    cut = len(wire.encode(first)) - 3
    a.sendall(data[:2])
    assert inbox.read() == []  # not even the length yet
    a.sendall(data[2:cut])
    assert inbox.read() == []
    a.sendall(data[cut:])
    got = inbox.read()
    assert [m[0] for m in got] == ["snap", "selected"]
    assert np.array_equal(got[0][1], first[1]) and got[1] == second


def test_a_full_socket_never_blocks_the_sender(pair: tuple[socket.socket, socket.socket]) -> None:
    """With nobody reading, put() returns at once and keeps what did not fit; the reader gets every message, whole
    and in order, once it reads and the sender flushes."""
    a, b = pair
    outbox, inbox = wire.Outbox(a), wire.Inbox(b)
    payload = b"x" * 200_000
    for i in range(40):  # 8 MB: far more than the socket buffers hold
        outbox.put(("blob", i, payload))
    assert not outbox.empty
    got: list[tuple[object, ...]] = []
    while not outbox.flush() or len(got) < 40:
        got += inbox.read()
    assert [m[1] for m in got] == list(range(40)) and all(m[2] == payload for m in got)


def test_a_closed_peer_is_said(pair: tuple[socket.socket, socket.socket]) -> None:
    """A message complete before the peer closed is still read; then PeerGone, for reading and for sending."""
    a, b = pair
    inbox = wire.Inbox(b)
    a.sendall(wire.encode(("pushed", 1, 0.0, 0.0)))
    a.close()
    assert inbox.read() == [("pushed", 1, 0.0, 0.0)]
    with pytest.raises(wire.PeerGone):
        inbox.read()
    with pytest.raises(wire.PeerGone):
        wire.Outbox(b).put(("play",))


def test_a_stream_that_is_no_viewers_is_refused(pair: tuple[socket.socket, socket.socket]) -> None:
    """A length beyond the limit (what another program's bytes look like) is a ValueError naming the size."""
    a, b = pair
    a.sendall(struct.pack("<I", wire.LIMIT + 1) + b"GET / HTTP/1.1")
    with pytest.raises(ValueError, match=f"a message of {wire.LIMIT + 1} bytes"):
        wire.Inbox(b).read()
