"""``sigcore ros topics / echo / hz / call / record`` against a real rclpy node in another process.

Each test starts its own peer (clients/tools_peer.py: a 20 Hz counter, a fixed PointStamped, a latched string, a
best-effort string, a sigcore_msgs topic, SetBool / SetEntityState / slow Trigger services) in a ROS domain of its
own, and runs ``python -m sigcore ros ...`` as subprocesses in that domain; every process is killed by process group
in ``finally``. DDS discovery on this machine takes up to about 3 s, so the commands get a generous ``--wait``
(they go on as soon as what they wait for appears). The first tests check the YAML and request helpers in-process.
"""

from __future__ import annotations

import json
import os
import re
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosproc import CLIENTS, _kill, ros_env  # noqa: E402

pytestmark = pytest.mark.ros2

WAIT = "8"
"""``--wait`` for the commands: discovery here takes up to ~3 s; they go on as soon as the topic appears [s]."""

POINT_YAML = """header:
  stamp:
    sec: 12
    nanosec: 345
  frame_id: peer_frame
point:
  x: 1.5
  y: -2.0
  z: 0.25
---
"""


# ---------------------------------------------------------------------- processes
class Peer:
    """clients/tools_peer.py in its own session and ROS domain; ``env`` is that domain's environment."""

    def __init__(self, log: Path) -> None:
        self.env = ros_env()
        self._log = open(log, "w")  # noqa: SIM115 - closed in stop()
        self.log = log
        self.proc = subprocess.Popen([sys.executable, str(CLIENTS / "tools_peer.py")], env=self.env,
                                     stdout=subprocess.PIPE, stderr=self._log, text=True, start_new_session=True)
        try:
            line = self._line(30.0)
            assert line and json.loads(line) == {"ready": True}, f"peer not ready: {line!r} {log.read_text()}"
        except BaseException:
            self.stop()
            raise

    def _line(self, timeout: float) -> str:
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        return self.proc.stdout.readline() if ready else ""

    def finish(self) -> dict[str, Any]:
        """Stop the peer with SIGINT: what it says it published last."""
        os.killpg(self.proc.pid, signal.SIGINT)
        out, _ = self.proc.communicate(timeout=10)
        lines = [line for line in out.splitlines() if line.startswith("{")]
        assert lines, f"peer printed nothing at the end; log: {self.log.read_text()[-2000:]}"
        result: dict[str, Any] = json.loads(lines[-1])
        return result

    def stop(self) -> None:
        _kill(self.proc)
        self._log.close()


@pytest.fixture
def peer(tmp_path: Path) -> Any:
    p = Peer(tmp_path / "peer.log")
    try:
        yield p
    finally:
        p.stop()


def start(env: dict[str, str], *args: str) -> subprocess.Popen[str]:
    """``python -m sigcore ros ARGS`` in its own session."""
    return subprocess.Popen([sys.executable, "-m", "sigcore", "ros", *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def finish(proc: subprocess.Popen[str], timeout: float = 25.0) -> tuple[int, str, str]:
    """Wait for a command started by :func:`start`: ``(exit status, stdout, stderr)``; killed on timeout."""
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill(proc)
        out, err = proc.communicate()
        raise AssertionError(f"sigcore ros {proc.args[4:]} timed out; stdout:\n{out[-2000:]}\nstderr:\n"  # type: ignore[index]
                             f"{err[-2000:]}") from None
    finally:
        _kill(proc)
    return proc.returncode, out, err


def run(env: dict[str, str], *args: str, timeout: float = 25.0) -> tuple[int, str, str]:
    return finish(start(env, *args), timeout)


def runs(env: dict[str, str], *commands: tuple[str, ...], timeout: float = 25.0) -> list[tuple[int, str, str]]:
    """Several commands at once (each in its own process); their results in order."""
    procs = [start(env, *c) for c in commands]
    try:
        return [finish(p, timeout) for p in procs]
    finally:
        for p in procs:
            _kill(p)


def one_line_error(err: str) -> str:
    """The command's error: exactly one line on stderr, no traceback."""
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in err and len(lines) == 1, err
    return lines[0]


# ---------------------------------------------------------------------- helpers, in-process
def test_yaml_of_a_message_is_like_ros2_topic_echo() -> None:
    """Fields in message order, nested mappings, floats as floats; arrays longer than the limit end in '...';
    --no-arr, --no-str and --field."""
    from geometry_msgs.msg import PointStamped
    from sensor_msgs.msg import JointState
    from sigcore_ros2.cli.yamltext import YamlStyle, field_of, to_yaml
    from std_msgs.msg import UInt8MultiArray

    p = PointStamped()
    p.header.stamp.sec, p.header.stamp.nanosec, p.header.frame_id = 12, 345, "peer_frame"
    p.point.x, p.point.y, p.point.z = 1.5, -2.0, 0.25
    assert to_yaml(p) + "---\n" == POINT_YAML
    assert to_yaml(field_of(p, ["point", "x"], "geometry_msgs/msg/PointStamped")) == "1.5\n"
    big = UInt8MultiArray(data=list(range(200)))
    data = to_yaml(big).split("data:\n", 1)[1].splitlines()
    assert data[:3] == ["- 0", "- 1", "- 2"] and data[127] == "- 127" and data[128] == "- '...'" and len(data) == 129
    assert to_yaml(big, YamlStyle(truncate=3)).endswith("data:\n- 0\n- 1\n- 2\n- '...'\n")
    assert len(to_yaml(big, YamlStyle(truncate=0)).split("data:\n", 1)[1].splitlines()) == 200
    j = JointState(name=["a", "b"], position=[0.5, 1.0])
    text = to_yaml(j, YamlStyle(no_arr=True, no_str=True))
    assert "position: '<sequence<double>, length: 2>'" in text and "frame_id: '<string, length: 0>'" in text
    from sigcore_ros2.exceptions import RosToolError

    with pytest.raises(RosToolError, match=r"point has no field 'w'; its fields: x, y, z"):
        field_of(p, ["point", "w"], "geometry_msgs/msg/PointStamped")


def test_requests_are_filled_from_yaml_and_refused_clearly() -> None:
    """Nested fields, ints for floats, sequences of messages; malformed YAML, unknown fields and values of the wrong
    type are refused naming the line, the valid fields, the field and its type; a type that is not installed names
    its package."""
    from geometry_msgs.msg import Polygon
    from sigcore_ros2.cli.messages import checked, fill, interface_class
    from sigcore_ros2.cli.yamltext import parse_request
    from sigcore_ros2.exceptions import RosToolError
    from simulation_interfaces.srv import SetEntityState

    req = fill(checked(SetEntityState.Request),
               parse_request("{entity: can, state: {header: {frame_id: world}, pose: {position: {x: 1, y: 2.5}}}}"),
               "request")
    assert (req.entity, req.state.header.frame_id, req.state.pose.position.x, req.state.pose.position.y) == \
        ("can", "world", 1.0, 2.5)
    poly = fill(checked(Polygon), parse_request("points: [{x: 1}, {y: 2}]"), "request")
    assert [(q.x, q.y) for q in poly.points] == [(1.0, 0.0), (0.0, 2.0)]
    assert parse_request("") == {}
    with pytest.raises(RosToolError, match=r"not valid YAML: .* at line 1, column 9"):
        parse_request("{data: [}")
    with pytest.raises(RosToolError, match="must be a YAML mapping"):
        parse_request("[1, 2]")
    with pytest.raises(RosToolError, match=r"request.state.pose.position has no field 'w'; its fields: x, y, z"):
        fill(checked(SetEntityState.Request), {"state": {"pose": {"position": {"w": 1}}}}, "request")
    with pytest.raises(RosToolError, match=r"request.state.header.stamp.sec is int32: '5000000000' does not fit"):
        fill(checked(SetEntityState.Request), {"state": {"header": {"stamp": {"sec": 5_000_000_000}}}}, "request")
    with pytest.raises(RosToolError, match=r"request.entity is string: '\[1\]'"):
        fill(checked(SetEntityState.Request), {"entity": [1]}, "request")
    with pytest.raises(RosToolError, match=r"type nosuch_msgs/msg/Thing cannot be imported: .*'nosuch_msgs'.*"
                                           r"install it"):
        interface_class("nosuch_msgs/msg/Thing")


# ---------------------------------------------------------------------- topics, echo
def test_topics_lists_the_peers_topics_with_types_and_counts(peer: Peer) -> None:
    """-t -c: each topic once, sorted, with its type and its publisher and subscriber counts (the tool's own node
    not counted: /parameter_events has the peer's publisher only); without options, names only (run one after the
    other: a second tool's node would count)."""
    rc, out, err = run(peer.env, "topics", "-t", "-c", "--wait", "5")
    assert rc == 0, err
    lines = out.splitlines()
    assert lines == sorted(lines) and len(set(lines)) == len(lines)
    assert "/peer/seq [std_msgs/msg/UInt32] (1 publisher, 0 subscribers)" in lines, out
    assert "/peer/cmd [std_msgs/msg/String] (0 publishers, 1 subscriber)" in lines, out
    assert "/peer/recv [sigcore_msgs/msg/OnRecvMsg] (1 publisher, 0 subscribers)" in lines, out
    assert "/parameter_events [rcl_interfaces/msg/ParameterEvent] (1 publisher, 0 subscribers)" in lines, out
    rc, names, err = run(peer.env, "topics", "--wait", "5")
    assert rc == 0 and {"/peer/seq", "/peer/point", "/peer/latched", "/peer/cmd"} <= set(names.splitlines()), names


def test_echo_once_prints_the_message_as_yaml(peer: Peer) -> None:
    """--once: the PointStamped's exact YAML; --field point.x: one value; a sigcore_msgs type."""
    (rc, out, err), (rc2, x, err2), (rc3, recv, err3) = runs(
        peer.env, ("echo", "/peer/point", "--once", "--wait", WAIT),
        ("echo", "peer/point", "--once", "--field", "point.x", "--wait", WAIT),
        ("echo", "/peer/recv", "--once", "--wait", WAIT))
    assert (rc, rc2, rc3) == (0, 0, 0), err + err2 + err3
    assert out == POINT_YAML
    assert x == "1.5\n---\n"
    assert re.fullmatch(r"sender: peer\ncontent: '\d+'\n---\n", recv), recv


def test_echo_gets_latched_and_best_effort_messages(peer: Peer) -> None:
    """A transient-local message published before echo started arrives (durability matched); a best-effort
    publisher is heard (reliability matched); --count 2 prints two messages."""
    time.sleep(0.5)  # the latched message is well in the past
    (rc, out, err), (rc2, best, err2) = runs(peer.env, ("echo", "/peer/latched", "--once", "--timeout", "15",
                                                        "--wait", WAIT),
                                             ("echo", "/peer/best_effort", "--count", "2", "--wait", WAIT))
    assert rc == 0 and out == "data: latched hello\n---\n", out + err
    assert rc2 == 0 and best == "data: best effort hello\n---\n" * 2, best + err2


def test_echo_of_an_unknown_topic_exits_2_listing_the_topics(peer: Peer) -> None:
    """One line naming the topic and the topics that exist; exit 2; a bad name is refused at once."""
    (rc, out, err), (rc2, _, err2) = runs(peer.env, ("echo", "/peer/nothing", "--once", "--wait", "5"),
                                          ("echo", "/bad name", "--once"))
    line = one_line_error(err)
    assert rc == 2 and out == "", err
    assert "/peer/nothing is not on the ROS 2 graph" in line and "/peer/seq" in line and "/peer/point" in line, line
    assert rc2 == 2 and "'/bad name' is not a valid topic name" in one_line_error(err2)


def test_echo_of_a_type_that_cannot_be_imported_exits_2(peer: Peer, tmp_path: Path) -> None:
    """The sigcore command runs where sigcore_msgs cannot be imported (a sitecustomize hides it): exit 2 naming
    the type and what to install."""
    (tmp_path / "sitecustomize.py").write_text(
        "import sys\n"
        "class _Hide:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'sigcore_msgs':\n"
        "            raise ModuleNotFoundError(f'No module named {name!r}', name=name)\n"
        "sys.meta_path.insert(0, _Hide())\n")
    env = dict(peer.env, PYTHONPATH=os.pathsep.join(p for p in (str(tmp_path), peer.env.get("PYTHONPATH")) if p))
    rc, out, err = run(env, "echo", "/peer/recv", "--once", "--wait", WAIT)
    line = one_line_error(err)
    assert rc == 2 and out == "", err
    assert "type sigcore_msgs/msg/OnRecvMsg cannot be imported" in line and "install" in line, line


# ---------------------------------------------------------------------- hz
def test_hz_reports_the_rate_of_a_20_hz_publisher(peer: Peer) -> None:
    """--duration 4 on the 20 Hz counter: exit 0, rate lines every second; the last rate is within 12-28 Hz (a wide
    margin: the machine is noisy), min <= 1/rate <= max. A topic nobody publishes: exit 1 saying so."""
    (rc, out, err), (rc2, out2, err2) = runs(peer.env, ("hz", "/peer/seq", "--duration", "4", "--wait", WAIT),
                                             ("hz", "/peer/cmd", "--duration", "2", "--wait", WAIT))
    assert rc == 0, err
    rates = [float(r) for r in re.findall(r"^average rate: ([\d.]+)$", out, re.M)]
    assert len(rates) >= 2, out
    assert 12.0 <= rates[-1] <= 28.0, out
    last = re.findall(r"min: ([\d.]+)s max: ([\d.]+)s std dev: ([\d.]+)s window: (\d+)", out)[-1]
    assert float(last[0]) <= 1 / rates[-1] <= float(last[1]) and int(last[3]) >= 20, out
    assert rc2 == 1 and out2 == "" and "no message on /peer/cmd in 2 s" in err2, err2


# ---------------------------------------------------------------------- call
def test_call_prints_the_response_as_yaml(peer: Peer) -> None:
    """SetBool with {data: true}; SetEntityState with a nested request: the responses' YAML."""
    (rc, out, err), (rc2, out2, err2) = runs(
        peer.env, ("call", "/peer/set_flag", "{data: true}", "--wait", WAIT),
        ("call", "/peer/set_state", "{entity: can, state: {header: {frame_id: world}, pose: {position: "
                                    "{x: 1, y: 2.5}}}}", "--wait", WAIT))
    assert rc == 0 and out == "success: true\nmessage: flag set to true\n", out + err
    assert rc2 == 0 and out2 == "result:\n  result: 1\n  error_message: can at 1 2.5 0 in world\n", out2 + err2


def test_call_refuses_bad_input_with_exit_2(peer: Peer) -> None:
    """Malformed YAML (its line and column), an unknown field (the valid ones), a value of the wrong type, an
    unknown service (the services that exist): one line each, exit 2."""
    results = runs(peer.env, ("call", "/peer/set_flag", "{data: [}", "--wait", WAIT),
                   ("call", "/peer/set_flag", "{flag: true}", "--wait", WAIT),
                   ("call", "/peer/set_flag", "{data: 3}", "--wait", WAIT),
                   ("call", "/peer/nothing", "{}", "--wait", "5"))
    lines = [one_line_error(err) for _, _, err in results]
    assert [rc for rc, _, _ in results] == [2, 2, 2, 2], lines
    assert all(out == "" for _, out, _ in results)
    assert "the request is not valid YAML" in lines[0] and "line 1, column 9" in lines[0], lines[0]
    assert "request has no field 'flag'; its fields: data" in lines[1], lines[1]
    assert "request.data is boolean: '3' does not fit" in lines[2], lines[2]
    assert "service /peer/nothing is not on the ROS 2 graph" in lines[3] and "/peer/set_flag" in lines[3], lines[3]


def test_call_without_a_response_in_time_exits_1(peer: Peer) -> None:
    """The peer's /peer/slow answers after 4 s; --timeout 1: exit 1 saying no response came."""
    rc, out, err = run(peer.env, "call", "/peer/slow", "--timeout", "1", "--wait", WAIT)
    assert rc == 1 and out == "" and "no response from /peer/slow within 1 s" in one_line_error(err), err


# ---------------------------------------------------------------------- record
def _read_bag(bag: Path) -> tuple[dict[str, Any], list[tuple[str, bytes]]]:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        connections = {c.topic: c for c in reader.connections}
        messages = [(c.topic, bytes(raw)) for c, _, raw in reader.messages()]
    return connections, messages


def test_record_writes_a_bag_of_what_the_peer_published(peer: Peer, tmp_path: Path) -> None:
    """Record three topics; stop the peer, then the recorder (SIGINT): the bag opens with rosbags; /peer/seq holds
    a contiguous run of the peer's counter up to the last one it published (only the start is missed, while
    discovering), with the right count and type; the latched string once; the sigcore_msgs type (registered from its
    .msg file) readable. The same directory again: exit 2."""
    from rclpy.serialization import deserialize_message
    from sigcore_msgs.msg import OnRecvMsg
    from std_msgs.msg import String, UInt32

    bag = tmp_path / "bag"
    proc = start(peer.env, "record", str(bag), "/peer/seq", "/peer/latched", "/peer/recv", "--wait", WAIT)
    try:
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and not (bag / "bag_0.mcap").exists():
            time.sleep(0.1)
        time.sleep(5.0)
        published = peer.finish()["seq"]
        time.sleep(1.0)
        os.killpg(proc.pid, signal.SIGINT)
        rc, out, err = finish(proc, 15)
    finally:
        _kill(proc)
    assert rc == 0, out + err
    assert (bag / "metadata.yaml").exists()
    connections, messages = _read_bag(bag)
    assert connections["/peer/seq"].msgtype == "std_msgs/msg/UInt32"
    assert connections["/peer/recv"].msgtype == "sigcore_msgs/msg/OnRecvMsg"
    seqs = [deserialize_message(raw, UInt32).data for topic, raw in messages if topic == "/peer/seq"]
    assert len(seqs) >= 20 and seqs == list(range(seqs[0], published + 1)), (seqs[:3], seqs[-3:], published)
    assert connections["/peer/seq"].msgcount == len(seqs)
    assert [deserialize_message(raw, String).data for t, raw in messages if t == "/peer/latched"] == ["latched hello"]
    recv = [deserialize_message(raw, OnRecvMsg) for t, raw in messages if t == "/peer/recv"]
    assert recv and all(m.sender == "peer" for m in recv)
    assert connections["/peer/latched"].ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL"
    assert re.search(rf"^  /peer/seq\s+{len(seqs)}  std_msgs/msg/UInt32$", out, re.M), out
    rc, out, err = run(peer.env, "record", str(bag), "/peer/seq")
    assert rc == 2 and "exists already" in one_line_error(err), err


def test_record_regex_for_a_duration(peer: Peer, tmp_path: Path) -> None:
    """--regex picks the matching topics (and no other); --duration ends it with a complete bag (metadata.yaml) and
    a summary whose counts are the bag's."""
    bag = tmp_path / "bag"
    rc, out, err = run(peer.env, "record", str(bag), "-e", "^/peer/(seq|point)$", "--duration", "6", "--wait", WAIT)
    assert rc == 0, out + err
    assert (bag / "metadata.yaml").exists()
    connections, messages = _read_bag(bag)
    assert set(connections) == {"/peer/seq", "/peer/point"}
    assert connections["/peer/point"].msgtype == "geometry_msgs/msg/PointStamped"
    for topic, c in connections.items():
        count = sum(1 for t, _ in messages if t == topic)
        assert count == c.msgcount > 0 and re.search(rf"^  {topic}\s+{count}  ", out, re.M), out
