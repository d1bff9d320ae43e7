"""The publication contract: declarations, sinks, latched values, the agents' publish entries, the static TF tree."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pytest

from sigcore.api.table import api_table
from sigcore.errors import PublicationError
from sigcore.publish import Offered, Publication, Publications, PublicationSink
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).parent.parent
SIM_WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"


class Recorder(PublicationSink):
    """A sink that keeps what it receives."""

    def __init__(self) -> None:
        self.declared: list[str] = []
        self.values: list[tuple[str, int, dict[str, Any]]] = []

    def declare(self, publication: Publication) -> None:
        self.declared.append(publication.topic)

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        self.values.append((publication.topic, stamp_ns, value))


class Broken(PublicationSink):
    """A sink whose every call raises (a transport's bug)."""

    def declare(self, publication: Publication) -> None:
        raise RuntimeError("broken declare")

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        raise RuntimeError("broken publish")


def test_bad_declarations_name_what_is_valid() -> None:
    """A bad topic, type or QoS class and a topic taken by another type are refused with what would be valid."""
    with pytest.raises(PublicationError, match="not a valid name"):
        Publication("/referee/ score", "std_msgs/msg/Int32", "latched")
    with pytest.raises(PublicationError, match="package/msg/Type"):
        Publication("/x", "std_msgs/Int32", "latched")
    with pytest.raises(PublicationError, match="state, sensor, events, latched, tf"):
        Publication("/x", "std_msgs/msg/Int32", "sometimes")  # type: ignore[arg-type]
    pubs = Publications(lambda: 0)
    pubs.declare(Publication("/x", "std_msgs/msg/Int32", "latched", origin="a"))
    with pytest.raises(PublicationError, match="already declared by a"):
        pubs.declare(Publication("/x", "std_msgs/msg/String", "latched", origin="b"))
    first = pubs.declare(Publication("/tf", "tf2_msgs/msg/TFMessage", "tf", origin="a"))
    second = pubs.declare(Publication("/tf", "tf2_msgs/msg/TFMessage", "tf", origin="b"))
    assert first.publication is second.publication  # /tf is shared, each declarer adds its own transforms


def test_a_sink_gets_past_and_future_declarations_and_the_latched_values() -> None:
    """A sink connected late is told of earlier declarations and gets the last latched value, then new ones."""
    now = [0]
    pubs = Publications(lambda: now[0])
    latched = pubs.declare(Publication("/result", "std_msgs/msg/String", "latched"))
    events = pubs.declare(Publication("/events", "std_msgs/msg/String", "events"))
    latched.publish({"data": "old"})
    latched.publish({"data": "new"})
    events.publish({"data": "lost: nobody listened"})
    assert not events.active
    sink = Recorder()
    pubs.connect(sink)
    assert events.active
    assert sink.declared == ["/result", "/events"]
    assert sink.values == [("/result", 0, {"data": "new"})]
    pubs.declare(Publication("/later", "std_msgs/msg/Int32", "state"))
    now[0] = 2_000_000
    events.publish({"data": "e"})
    events.publish({"data": "f"}, stamp_ns=5)
    assert sink.declared[-1] == "/later"
    assert sink.values[1:] == [("/events", 2_000_000, {"data": "e"}), ("/events", 5, {"data": "f"})]
    pubs.disconnect(sink)
    events.publish({"data": "g"})
    assert len(sink.values) == 3


def test_a_failing_sink_is_logged_once_and_others_still_get_every_value(caplog: pytest.LogCaptureFixture) -> None:
    """A sink that raises never stops a publisher nor the other sinks; its failure is logged once per topic."""
    pubs = Publications(lambda: 0)
    pub = pubs.declare(Publication("/x", "std_msgs/msg/Int32", "events"))
    good = Recorder()
    with caplog.at_level(logging.ERROR, logger="sigcore"):
        pubs.connect(Broken())
        pubs.connect(good)
        for i in range(5):
            pub.publish({"data": i})
    assert [v[2]["data"] for v in good.values] == [0, 1, 2, 3, 4]
    assert len([r for r in caplog.records if "publish of /x" in r.getMessage()]) == 1


def test_agent_publications_come_from_the_api_table() -> None:
    """Every publish entry of the table is one publication per agent that has it (scans: robots with a lidar)."""
    sim = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")
    topics = {p.topic: p for p in sim.publications.declared}
    for entry in (e for e in api_table() if e.direction == "publish"):
        for agent, handle in sim.entities.items():
            expected = handle.kind in entry.kinds and (entry.suffix != "_scan" or any(
                lidar.robot == agent for lidar in sim.entities.lidars))
            assert (entry.name_for(agent) in topics) == expected, (entry.suffix, agent)
    scan = topics["robot_000_scan"]
    assert (scan.msg_type, scan.qos, scan.agent) == ("sensor_msgs/msg/LaserScan", "sensor", "robot_000")
    assert topics["moderator_0_onRecvMsg"].full_type == "sigcore_msgs/msg/OnRecvMsg"


def test_event_sources_are_attached_only_when_a_sink_connects() -> None:
    """Without a sink nothing listens to collisions (the step skips contact events); with one, each message and
    each scan arrives as a field dictionary stamped with its step."""
    sim = Simulation(parse_world(SIM_WORLD), "mujoco")
    assert not sim.events.subscriptions("collision") and not sim.events.subscriptions("scan")
    sink = Recorder()
    sim.publications.connect(sink)
    assert sim.events.subscriptions("collision") and sim.events.subscriptions("scan")
    sim.send_msg("someone", "bot", "hello")
    sim.step(200)
    scans = [(stamp, v) for topic, stamp, v in sink.values if topic == "bot_scan"]
    assert len(scans) == 4  # 10 Hz for 0.4 s (2 ms steps)
    stamp, value = scans[0]
    assert stamp % round(sim.dt * 1e9) == 0 and value["header"]["stamp"] == stamp
    assert value["header"]["frame_id"] == "laser_link" and len(value["ranges"]) == 180
    assert [(stamp, v) for topic, stamp, v in sink.values if topic == "bot_onRecvMsg"] == [
        (0, {"sender": "someone", "content": "hello"})]


def test_the_static_tree_has_one_parent_per_frame_and_slam_reparents_odom(tmp_path: Path) -> None:
    """/tf_static holds world -> odom and the fixed joints; with SLAM, world -> map replaces world -> odom."""
    sim = Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")
    static = sim.frames.static()
    assert static["odom"][0] == "world"
    latest = sim.publications.latest("/tf_static")
    assert latest is not None
    assert {t["child_frame_id"] for t in latest[1]["transforms"]} == set(static)
    text = (ROOT / "worlds" / "cleanup.xml").read_text().replace(
        "</world>", '  <plugin name="slam" agent="robot_000"/>\n</world>')
    world = tmp_path / "cleanup_slam.xml"
    world.write_text(text.replace('urdf="models/', f'urdf="{ROOT}/worlds/models/'))
    slam = Simulation(parse_world(world), "mujoco")
    static = slam.frames.static()
    assert "odom" not in static and static["map"][0] == "world"
    latest = slam.publications.latest("/tf_static")
    assert latest is not None and "odom" not in {t["child_frame_id"] for t in latest[1]["transforms"]}
    topics = {p.topic: p.origin for p in slam.publications.declared}
    assert topics["/map"] == topics["/robot_000/slam_pose"] == "slam"


class RawTaker(Recorder):
    """A sink that also takes the transports' own serialized messages (a recorder)."""

    takes_raw = True

    def __init__(self, fail: bool = False) -> None:
        super().__init__()
        self.raws: list[tuple[str, str, Offered, int, bytes]] = []
        self.fail = fail

    def raw(self, topic: str, msg_type: str, offered: Offered, stamp_ns: int, data: bytes) -> None:
        if self.fail:
            raise RuntimeError("broken raw")
        self.raws.append((topic, msg_type, offered, stamp_ns, data))


def test_raw_messages_reach_only_sinks_that_take_them(caplog: pytest.LogCaptureFixture) -> None:
    """raw_wanted is true only while a sink that takes raw messages is connected; those sinks get each one (a
    failing one is logged once and the others still get them); the others never see them."""
    pubs = Publications(lambda: 0)
    plain, taker, broken = Recorder(), RawTaker(), RawTaker(fail=True)
    pubs.connect(plain)
    assert not pubs.raw_wanted
    pubs.connect(broken)
    pubs.connect(taker)
    assert pubs.raw_wanted
    offered = Offered(1, latched=True)
    with caplog.at_level(logging.ERROR, logger="sigcore"):
        for i in range(3):
            pubs.raw("/clock", "rosgraph_msgs/msg/Clock", offered, i, b"\x00\x01\x00\x00" + bytes([i]))
    assert [(t, s, d[-1]) for t, _, _, s, d in taker.raws] == [("/clock", 0, 0), ("/clock", 1, 1), ("/clock", 2, 2)]
    assert taker.raws[0][2] == offered and not plain.values
    assert sum("raw /clock by RawTaker failed" in r.getMessage() for r in caplog.records) == 1
    pubs.disconnect(taker)
    pubs.disconnect(broken)
    assert not pubs.raw_wanted
