"""Recording runs (issue 15, part 1): the clean-up task with the scripted robot and no ROS 2, recorded by
``sigcore.record.Recorder`` and read back with independent readers (rosbags for the messages and metadata, mcap's
reader for the attachments); the CLI's --record options and their bad input; ``sigcore bag info`` on whole, cut and
foreign bags; a full disk (a real file size limit) during a run."""

from __future__ import annotations

import resource
import shutil
import signal
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from sigcore.publish import Publication, PublicationSink
from sigcore.record import GROUND_TRUTH, Recorder
from sigcore.record.bag_reading import bag_info
from sigcore.record.exceptions import SerializeError
from sigcore.record.recorder import _TfLayout
from sigcore.record.serialize import Serializer
from sigcore.sim import Simulation, run
from sigcore.sim.exceptions import ReplayError
from sigcore.sim.inputs import Input, refusal
from sigcore.world import parse_world
from sigcore.world.exceptions import SpawnRefusal
from sigcore.world.resources import SpawnRequest

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
SIGCORE = [sys.executable, "-m", "sigcore"]
SCRIPTED = ("--transport", "none", "--controller", "robot_000=cleanup.robot")


class _Count(PublicationSink):
    """Counts every value the simulation publishes, per full topic name, with its stamps."""

    def __init__(self) -> None:
        self.stamps: dict[str, list[int]] = {}

    def declare(self, publication: Publication) -> None:
        self.stamps.setdefault(_full(publication.topic), [])

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        self.stamps.setdefault(_full(publication.topic), []).append(stamp_ns)


def _full(topic: str) -> str:
    return topic if topic.startswith("/") else "/" + topic


def _read(path: Path) -> tuple[dict[str, Any], list[tuple[str, int, Any]]]:
    """Every connection (by topic) and every message (topic, log time, deserialized) of a bag, with rosbags."""
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        connections = {c.topic: c for c in reader.connections}
        messages = [(c.topic, t, reader.deserialize(raw, c.msgtype)) for c, t, raw in reader.messages()]
    return connections, messages


@pytest.fixture(scope="module")
def cleanup(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The clean-up task run to its end by the scripted robot (MuJoCo, no transport), recorded; a sink beside
    the recorder counts what was published."""
    path = tmp_path_factory.mktemp("record") / "cleanup_bag"
    sim = Simulation(parse_world(CLEANUP), "mujoco", {"robot_000": "cleanup.robot"})
    recorder = Recorder(sim, path)
    count = _Count()
    sim.publications.connect(count)
    report = run(sim, duration=300)
    recorder.close()
    connections, messages = _read(path)
    truth = sim.backend.get_poses([(n, None) for n in sim.scene.entities])
    return {"path": path, "report": report, "published": count.stamps, "connections": connections,
            "messages": messages, "dt_ns": round(sim.dt * 1e9), "end_ns": sim.stamp_ns(),
            "box": sim.scene.bounds("trashbox_2"), "final": dict(zip(sim.scene.entities, truth, strict=True)),
            "every": recorder._every}


@pytest.mark.slow
def test_the_task_ran_to_its_end_while_recording(cleanup: dict) -> None:
    """Recording changes nothing in the run: the task succeeds with the usual score."""
    assert cleanup["report"].summary["referee"]["result"] == "succeeded"
    assert cleanup["report"].summary["referee"]["score"] == 3150


@pytest.mark.slow
def test_every_published_message_is_in_the_bag_with_its_stamp(cleanup: dict) -> None:
    """For every declared topic, the bag holds exactly the messages that were published, in order, each logged at
    the simulated time it was stamped with (the referee's 7 events among them)."""
    recorded: dict[str, list[int]] = {}
    for topic, t, _ in cleanup["messages"]:
        recorded.setdefault(topic, []).append(t)
    published = cleanup["published"]
    assert published["/referee/events"] and len(published["/referee/events"]) == 7
    for topic, stamps in published.items():
        assert recorded.get(topic, []) == stamps, topic
    assert set(recorded) - set(published) == {GROUND_TRUTH}


@pytest.mark.slow
def test_the_metadata_counts_what_the_file_holds(cleanup: dict) -> None:
    """metadata.yaml (read by rosbags) names every topic with its type hash and counts what rosbags reads."""
    counts = Counter(topic for topic, _, _ in cleanup["messages"])
    for topic, connection in cleanup["connections"].items():
        assert connection.msgcount == counts.get(topic, 0), topic
        assert connection.digest.startswith("RIHS01_") and len(connection.digest) == 7 + 64
    assert cleanup["connections"]["/referee/events"].msgtype == "sigcore_msgs/msg/RefereeEvent"


@pytest.mark.slow
def test_latched_topics_are_offered_transient_local(cleanup: dict) -> None:
    """/tf_static, robot_description and the referee's result keep their latched QoS, so a player replays them
    latched; the events stay volatile and reliable."""
    connections = cleanup["connections"]
    for topic in ("/tf_static", "/robot_description", "/referee/result"):
        qos = connections[topic].ext.offered_qos_profiles
        assert qos and qos[0].durability.name == "TRANSIENT_LOCAL" and qos[0].depth == 1, topic
    events = connections["/referee/events"].ext.offered_qos_profiles[0]
    assert events.durability.name == "VOLATILE" and events.reliability.name == "RELIABLE"


@pytest.mark.slow
def test_ground_truth_is_at_its_rate_and_ends_at_the_last_step(cleanup: dict) -> None:
    """/sigcore/ground_truth: a TFMessage world -> ground_truth/<frame> for every frame (each robot link too),
    logged and stamped at every 17th step (30 Hz at 2 ms), plus the last step; its last poses are the final ones."""
    truth = [(t, m) for topic, t, m in cleanup["messages"] if topic == GROUND_TRUTH]
    period = cleanup["every"] * cleanup["dt_ns"]
    assert cleanup["every"] == 17
    times = [t for t, _ in truth]
    assert times[:-1] == [i * period for i in range(len(times) - 1)]
    assert times[-1] == cleanup["end_ns"]
    for t, m in truth[::200]:
        assert all(tf.header.stamp.sec * 10**9 + tf.header.stamp.nanosec == t for tf in m.transforms)
    last = {tf.child_frame_id: tf.transform for tf in truth[-1][1].transforms}
    assert "ground_truth/robot_000/base_link" in last and "ground_truth/robot_000/l_hand_link" in last
    for name, pose in cleanup["final"].items():
        frame = f"ground_truth/{name}/base_link" if name == "robot_000" else f"ground_truth/{name}"
        got = last[frame]
        assert [got.translation.x, got.translation.y, got.translation.z] == list(pose[:3]), name
        assert [got.rotation.w, got.rotation.x, got.rotation.y, got.rotation.z] == list(pose[3:]), name


@pytest.mark.slow
def test_can_0_is_inside_its_box_at_its_correct_box_event(cleanup: dict) -> None:
    """The ground truth of can_0 nearest to the referee's 'can_0 in trashbox_2' event lies inside trashbox_2."""
    events = [(t, m) for topic, t, m in cleanup["messages"] if topic == "/referee/events"]
    at = next(t for t, m in events if m.kind == "correct_box" and "can_0" in m.text)
    truth = [(t, m) for topic, t, m in cleanup["messages"] if topic == GROUND_TRUTH]
    t, message = min(truth, key=lambda tm: abs(tm[0] - at))
    assert abs(t - at) <= cleanup["every"] * cleanup["dt_ns"]
    can = next(tf.transform.translation for tf in message.transforms if tf.child_frame_id == "ground_truth/can_0")
    low, high = cleanup["box"]
    assert low[0] < can.x < high[0] and low[1] < can.y < high[1] and low[2] < can.z < high[2], (can, low, high)


@pytest.mark.slow
def test_the_world_file_and_its_urdfs_are_attached(cleanup: dict) -> None:
    """The world file and the URDFs it uses are MCAP attachments, byte for byte (read with mcap's reader), and
    the run's facts are a metadata record."""
    from mcap.reader import make_reader

    with open(next(cleanup["path"].glob("*.mcap")), "rb") as f:
        reader = make_reader(f)
        attachments = {a.name: a.data for a in reader.iter_attachments()}
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    assert attachments["world/cleanup.xml"] == CLEANUP.read_bytes()
    assert attachments["world/models/sigbot/sigbot.urdf"] == (ROOT / "worlds/models/sigbot/sigbot.urdf").read_bytes()
    assert metadata["sigcore"]["backend"] == "mujoco" and metadata["sigcore"]["timestep"] == "0.002"


@pytest.mark.slow
def test_bag_info_lists_topics_counts_and_attachments(cleanup: dict) -> None:
    """sigcore bag info on the whole bag: exit 0, the topics with their counts, the times, the attachments."""
    out = subprocess.run([*SIGCORE, "bag", "info", str(cleanup["path"])], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    events = Counter(topic for topic, _, _ in cleanup["messages"])["/referee/events"]
    assert "Topic: /referee/events" in out.stdout and f"Count: {events} " in out.stdout
    assert "world/cleanup.xml (application/xml" in out.stdout and "Problem" not in out.stdout
    assert f"End:               {cleanup['end_ns'] / 1e9:.3f}" in out.stdout


@pytest.mark.slow
def test_a_cut_bag_is_reported_not_a_traceback(cleanup: dict, tmp_path: Path) -> None:
    """A recording killed mid-way (no metadata.yaml, its MCAP file cut inside a record): bag info says what is
    wrong, names the file, lists what is readable, and exits 1."""
    cut = tmp_path / "cut"
    shutil.copytree(cleanup["path"], cut)
    (cut / "metadata.yaml").unlink()
    mcap = next(cut.glob("*.mcap"))
    size = mcap.stat().st_size
    with open(mcap, "r+b") as f:
        f.truncate(size // 2 + 3)
    out = subprocess.run([*SIGCORE, "bag", "info", str(cut)], capture_output=True, text=True, timeout=60)
    assert out.returncode == 1, out.stdout + out.stderr
    assert "Traceback" not in out.stdout + out.stderr
    assert "metadata.yaml is missing" in out.stdout and f"{mcap} is cut or damaged" in out.stdout
    assert "Topic: /sigcore/ground_truth" in out.stdout


@pytest.mark.slow
def test_a_foreign_or_missing_bag_is_refused_by_name(tmp_path: Path) -> None:
    """A file that is not MCAP, a directory without one and a missing path: exit 2, one line naming it."""
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign" / "x.mcap").write_text("not a recording\n")
    (tmp_path / "empty").mkdir()
    for target, says in ((tmp_path / "foreign", "is not an MCAP file"), (tmp_path / "empty", "holds no .mcap file"),
                         (tmp_path / "nowhere", "no such file or directory")):
        out = subprocess.run([*SIGCORE, "bag", "info", str(target)], capture_output=True, text=True, timeout=60)
        assert out.returncode == 2 and says in out.stderr and "Traceback" not in out.stderr, out.stderr


def _run(*args: str, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*SIGCORE, "run", str(CLEANUP), *SCRIPTED, "-q", *args], capture_output=True, text=True,
                          timeout=300, **kwargs)


@pytest.mark.slow
def test_an_existing_directory_is_refused_unless_overwrite(tmp_path: Path) -> None:
    """--record into a directory that exists: exit 2 naming it and --overwrite; --overwrite replaces a recording,
    never a directory holding other files."""
    bag = tmp_path / "bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("old\n")
    out = _run("--duration", "0.1", "--record", str(bag))
    assert out.returncode == 2 and f"{bag} exists already" in out.stderr and "--overwrite" in out.stderr
    assert (bag / "metadata.yaml").read_text() == "old\n"
    out = _run("--duration", "0.1", "--record", str(bag), "--overwrite")
    assert out.returncode in (0, 1) and "recording:" in out.stdout, out.stderr
    assert bag_info(bag).problems == [] and (bag / "metadata.yaml").read_text() != "old\n"
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me\n")
    out = _run("--duration", "0.1", "--record", str(mine), "--overwrite")
    assert out.returncode == 2 and "notes.txt" in out.stderr and (mine / "notes.txt").exists()


@pytest.mark.slow
def test_record_topics_selects_and_a_bad_pattern_is_refused(tmp_path: Path) -> None:
    """--record-topics keeps only the matching topics (and the ground truth); an invalid regex is exit 2 naming
    it; --record-topics without --record is refused."""
    bag = tmp_path / "some"
    out = _run("--duration", "1", "--record", str(bag), "--record-topics", "^/referee/", "--record-topics", "scan$")
    assert out.returncode in (0, 1), out.stderr
    topics = {t.name for t in bag_info(bag).topics}
    assert topics == {"/referee/events", "/referee/score", "/referee/result", "/robot_000_scan", GROUND_TRUTH}
    out = _run("--duration", "1", "--record", str(tmp_path / "bad"), "--record-topics", "(oops")
    assert out.returncode == 2 and "'(oops' is not a regular expression" in out.stderr
    assert not (tmp_path / "bad").exists()
    out = _run("--duration", "1", "--record-topics", "x")
    assert out.returncode == 2 and "--record DIR" in out.stderr


def _limit_file_size() -> None:
    """In the child: files may not grow beyond 400 KiB (a write past it fails with EFBIG instead of a signal)."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (400 * 1024, 400 * 1024))


@pytest.mark.slow
def test_a_full_disk_stops_the_recording_not_the_run(tmp_path: Path) -> None:
    """A real write failure (a file size limit, EFBIG) 30 s into a 60 s run: the run goes on to its end, the
    recording says it stopped early and why, and the bag so far is readable by rosbags with metadata.yaml counting
    exactly what the file holds."""
    bag = tmp_path / "full"
    out = _run("--duration", "60", "--record", str(bag), preexec_fn=_limit_file_size)
    assert out.returncode in (0, 1), out.stdout + out.stderr
    assert "steps:    30000" in out.stdout
    assert "stopped early: writing" in out.stdout and "File too large" in out.stdout
    assert "Traceback" not in out.stderr
    connections, messages = _read(bag)
    counts = Counter(topic for topic, _, _ in messages)
    assert counts[GROUND_TRUTH] > 10
    assert all(c.msgcount == counts.get(t, 0) for t, c in connections.items())
    info = bag_info(bag)
    assert info.problems == [] and info.messages == len(messages)
    assert max(t for _, t, _ in messages) < 60 * 10**9


def test_the_ground_truth_layout_is_the_standard_serialization() -> None:
    """The recorder's fixed-layout TFMessage is byte for byte what rosbags serializes for the same message."""
    children = ["ground_truth/a", "ground_truth/robot/base_link", "ground_truth/xyz"]
    poses = np.array([[1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0], [-0.5, 0.25, 0.125, 0.5, 0.5, 0.5, 0.5],
                      [1e-9, -7.0, 2.5, 0.0, 0.0, 0.0, 1.0]])
    stamp = 12_345_678_901
    fields = {"transforms": [{"header": {"stamp": stamp, "frame_id": "world"}, "child_frame_id": c,
                              "transform": {"translation": {"x": p[0], "y": p[1], "z": p[2]},
                                            "rotation": {"w": p[3], "x": p[4], "y": p[5], "z": p[6]}}}
                             for c, p in zip(children, poses, strict=True)]}
    assert _TfLayout("world", children).pack(stamp, poses) == Serializer().serialize("tf2_msgs/msg/TFMessage",
                                                                                      fields)


def test_the_serializer_names_what_does_not_fit() -> None:
    """An unknown field names the type's fields; an unknown type and a value of the wrong kind are named too."""
    s = Serializer()
    with pytest.raises(SerializeError, match="has no field 'dta'; fields: data"):
        s.serialize("std_msgs/msg/String", {"dta": "x"})
    with pytest.raises(SerializeError, match="nope_msgs/msg/X"):
        s.definition("nope_msgs/msg/X")
    with pytest.raises(SerializeError, match="std_msgs/msg/Int32"):
        s.serialize("std_msgs/msg/Int32", {"data": "many"})




# ---------------------------------------------------------------------- the input log and replays (no ROS 2)
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"


def _drive_and_record(path: Path) -> Simulation:
    """tests/data/sim/world.xml recorded while this test acts as a transport would: API calls between steps
    (wheels, a joint target, a teleport of the cube, a force on the ball) and a reset; 1500 steps."""
    from sigcore.api.call import call

    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, path)
    entries = {e.suffix: e for e in sim.api_entries()}
    plan = {0: ("bot", "_setWheelVelocity", {"left_wheel": 4.0, "right_wheel": 2.5}),
            200: ("bot", "_setJointTarget", {"joint_name": "shoulder_joint", "angle": 0.6}),
            450: ("cube", "_setPosition", {"x": 0.4, "y": -0.3, "z": 0.6}),
            700: ("ball", "_addForce", {"x": 30.0, "y": 0.0, "z": 0.0}),
            1100: ("bot", "_setWheelVelocity", {"left_wheel": -3.0, "right_wheel": 3.0})}
    sim.start()
    for step in range(1500):
        if step in plan:
            agent, suffix, request = plan[step]
            answer = call(sim, entries[suffix], agent, request)
            assert answer["success"], answer
        if step == 900:
            sim.reset()
        sim.step()
    sim.stop()
    recorder.close()
    return sim


def test_a_replay_applies_each_command_at_its_step_bit_for_bit(tmp_path: Path) -> None:
    """The input log holds the calls and the reset at their steps; a Replayer applying them reproduces every
    frame's pose at the end bit for bit; the same replay without the reset does not (the comparison can fail)."""
    from sigcore.record.replay import Replayer, compare, load_recording, poses_now

    _drive_and_record(tmp_path / "bag")
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind) for i in rec.inputs] == [(0, "api"), (200, "api"), (450, "api"), (700, "api"),
                                                      (900, "reset"), (1100, "api")]
    assert rec.inputs[2].args == {"agent": "cube", "entry": "_setPosition",
                                  "request": {"name": "", "x": 0.4, "y": -0.3, "z": 0.6}}
    assert rec.final_step == 1500

    def replay(inputs: list) -> tuple[bool, float, str]:
        sim = Simulation(rec.world(tmp_path / "world"), "mujoco", rec.controllers)
        run(sim, steps=rec.final_step, transport=[Replayer(inputs)])
        return compare(rec.truth[-1][1], poses_now(sim))

    equal, worst, _ = replay(rec.inputs)
    assert equal and worst == 0.0
    equal, worst, where = replay([i for i in rec.inputs if i.kind != "reset"])
    assert not equal and worst > 1e-3, (worst, where)


def _spawn_and_record(path: Path, pebble: Path) -> None:
    """tests/data/sim/world.xml recorded for 1000 steps while this test applies and notes what the ROS 2 plugin
    applies and notes for spawn_entities, delete_entity and set_entity_info: at step 100 one batch of three
    requests (a box from its resource text dropped on the ball, the file ``pebble`` as 'crate' renamed to 'crate_1'
    dropped on the cube, a missing file, refused), at step 400 the cube deleted (the pebble falls), at step 500 the
    heavy box's information changed."""
    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, path)
    sim.start()
    for step in range(1000):
        if step == 100:
            requests = [SpawnRequest(name="crate", resource='<object shape="box" size="0.1 0.1 0.1" mass="1"/>',
                                     xyz=(-0.96, 1.0, 0.3), wxyz=(0.9659258, 0.0, 0.0, 0.2588190), tags=("trash",)),
                        SpawnRequest(name="crate", uri=str(pebble), xyz=(0.6, 0.5, 0.3), allow_renaming=True),
                        SpawnRequest(uri="missing.urdf")]
            outcomes = sim.entities.spawn(requests)
            assert outcomes[:2] == ["crate", "crate_1"] and isinstance(outcomes[2], SpawnRefusal), outcomes
            sim.inputs.note_spawn(requests, outcomes, what="spawn_entities (3)")  # as siminterfaces notes it
        if step == 400:
            sim.entities.delete(["cube"])
            sim.inputs.note("delete", entities=["cube"], what="delete_entity cube")
        if step == 500:
            info = sim.entities.info.set("heavy", "dynamic_object", "pushed around", ["furniture", "moved"])
            sim.inputs.note("entity_info", entity="heavy", category=info.category, description=info.description,
                            tags=list(info.tags), what="set_entity_info heavy")
        sim.step()
    sim.stop()
    recorder.close()


def test_a_replay_reproduces_spawns_deletes_and_entity_info(tmp_path: Path) -> None:
    """A run with a spawn batch (renaming and a refusal in it), a delete and an entity information change: the log
    holds every request's fields and outcome; a Replayer reproduces every frame's pose bit for bit and the
    information; without the spawn the ball is not knocked away and without the delete the pebble stays up (the
    comparison fails); with the pebble's file gone the replay stops at the spawn naming the step, the uri and the
    core's refusal."""
    from sigcore.record.replay import Replayer, compare, load_recording, poses_now

    pebble = tmp_path / "pebble.xml"
    pebble.write_text('<object shape="sphere" size="0.03" mass="0.1"/>\n')
    _spawn_and_record(tmp_path / "bag", pebble)
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind) for i in rec.inputs] == [(100, "spawn"), (400, "delete"), (500, "entity_info")]
    spawn = rec.inputs[0].args
    assert spawn["requests"][0] == {"name": "crate", "uri": "", "resource": '<object shape="box" size="0.1 0.1 0.1" '
                                    'mass="1"/>', "xyz": [-0.96, 1.0, 0.3], "wxyz": [0.9659258, 0.0, 0.0, 0.2588190],
                                    "frame": "", "namespace": "", "allow_renaming": False, "tags": ["trash"]}
    assert [r["uri"] for r in spawn["requests"]] == ["", str(pebble), "missing.urdf"]
    assert spawn["names"] == ["crate", "crate_1", None]
    assert rec.inputs[1].args["entities"] == ["cube"]
    assert rec.inputs[2].args == {"entity": "heavy", "category": "dynamic_object", "description": "pushed around",
                                  "tags": ["furniture", "moved"], "what": "set_entity_info heavy"}
    recorded = rec.truth[-1][1]
    assert rec.final_step == 1000 and "ground_truth/crate_1" in recorded and "ground_truth/cube" not in recorded

    def replay(inputs: list) -> tuple[Simulation, Replayer]:
        sim = Simulation(rec.world(tmp_path / "world"), "mujoco", rec.controllers)
        replayer = Replayer(inputs)
        run(sim, steps=rec.final_step, transport=[replayer])
        return sim, replayer

    sim, replayer = replay(rec.inputs)
    equal, worst, _ = compare(recorded, poses_now(sim))
    assert replayer.error is None and replayer.applied == 3 and equal and worst == 0.0
    heavy = sim.entities.info.get("heavy")
    assert heavy.category == "dynamic_object" and heavy.tags == ("furniture", "moved")
    assert sim.entities.info.get("crate").tags == ("trash",)

    sim, _ = replay([i for i in rec.inputs if i.kind != "spawn"])
    now = poses_now(sim)
    assert not compare(recorded, now)[0]
    assert np.linalg.norm(recorded["ground_truth/ball"][:3] - now["ground_truth/ball"][:3]) > 0.5  # knocked away
    sim, _ = replay([i for i in rec.inputs if i.kind != "delete"])
    now = poses_now(sim)
    assert not compare(recorded, now)[0] and now["ground_truth/crate_1"][2] - recorded["ground_truth/crate_1"][2] > 0.04

    pebble.unlink()
    sim, replayer = replay(rec.inputs)
    assert sim.step_count == 100 and replayer.applied == 0 and replayer.error is not None
    assert replayer.error.startswith(f"step 100: the spawn of uri '{pebble}' (name 'crate') is refused now "
                                     f"(NOT_FOUND: no file for uri '{pebble}'"), replayer.error


def test_replay_refuses_commands_recorded_without_their_arguments() -> None:
    """A spawn, delete or entity_info input as sigcore noted them before they were replayed (only ``what``) and a
    world load are refused, naming the step and offering --until; the full forms are replayable."""
    sim = Simulation(parse_world(WORLD), "mujoco")
    for kind, what in [("spawn", "spawn_entity crate"), ("delete", "delete_entity cube"),
                       ("entity_info", "set_entity_info cube"), ("world", "load_world other")]:
        item = Input(7, kind, {"what": what})
        why = refusal(item)
        assert why is not None and why.startswith(f"step 7: the run applied '{what}'") and "--until 7" in why
        with pytest.raises(ReplayError, match=f"step 7: the run applied '{what}'"):
            sim.inputs.apply(item)
    assert refusal(Input(7, "delete", {"entities": ["cube"]})) is None
    sim.inputs.apply(Input(7, "delete", {"entities": ["cube"]}))
    assert "cube" not in sim.entities.names
    with pytest.raises(ReplayError, match="step 7: deleting 'cube' is refused now .NOT_FOUND"):
        sim.inputs.apply(Input(7, "delete", {"entities": ["cube"]}))


def test_a_world_load_is_recorded_in_log_order_and_not_replayed(tmp_path: Path) -> None:
    """A world loaded while recording (noted as the ROS 2 plugin notes load_world) restarts the step count: the
    recording goes on with the new world's frames (no stale frames of the old one), the input log is read back in
    the order applied (a command of the new world's step 20 after the load at step 300), a replay up to step 100
    applies only the old world's commands, and the load is refused naming its step."""
    from sigcore.record.replay import Replayer, load_recording

    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag", ground_truth_rate=100)
    sim.step(50)
    sim.entities.delete(["cube"])
    sim.inputs.note("delete", entities=["cube"], what="delete_entity cube")
    sim.step(250)
    camera = ROOT / "tests" / "data" / "sim" / "camera.xml"
    sim.inputs.note("world", what="load_world camera", uri=str(camera), resource_string="")
    sim.worlds.load(parse_world(camera))
    sim.step(20)
    info = sim.entities.info.set("can", "dynamic_object", "", [])
    sim.inputs.note("entity_info", entity="can", category=info.category, description="", tags=[])
    sim.step(80)
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind) for i in rec.inputs] == [(50, "delete"), (300, "world"), (20, "entity_info")]
    assert rec.final_step == 100 and "ground_truth/can" in rec.truth[-1][1]
    assert "ground_truth/ball" not in rec.truth[-1][1] and "ground_truth/ball" in rec.truth[0][1]
    assert Replayer(rec.inputs, until=100).pending == 1 and Replayer(rec.inputs).pending == 3
    why = refusal(rec.inputs[1])
    assert why is not None and why.startswith("step 300: the run applied 'load_world camera', which replay does not "
                                              "reproduce yet") and "--until 300" in why


@pytest.mark.slow
def test_replay_cli_checks_and_refuses_what_it_cannot_reproduce(tmp_path: Path) -> None:
    """sigcore replay of that recording: exit 0, every ground-truth frame 'bitwise equal', the commands counted;
    the referee's topics, not recorded, said to be not compared; a recording whose input
    log holds a spawn noted as sigcore noted one before spawns were replayed (only 'what'), or a world load, is
    refused before it runs, naming the step and offering --until; --until before it replays up to there, --until
    after a world load is refused; a spawn whose file is gone stops the replay there (exit 3) naming the step, the
    uri and the refusal, no traceback."""
    _drive_and_record(tmp_path / "bag")
    out = subprocess.run([*SIGCORE, "replay", str(tmp_path / "bag")], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "6 commands applied (of 6 recorded)" in out.stdout, out.stdout
    # every 17th step at 30 Hz and 2 ms: 0, 17, ..., 1496, and the last step
    assert "ground truth: all 90 recorded messages (steps 0 to 1500) bitwise equal" in out.stdout, out.stdout
    assert "referee: no score, events or result recorded" in out.stdout and "not compared" in out.stdout

    for name, kind, what in [("spawned", "spawn", "spawn_entity crate"), ("world", "world", "load_world other")]:
        sim = Simulation(parse_world(WORLD), "mujoco")
        recorder = Recorder(sim, tmp_path / name)
        sim.step(100)
        sim.inputs.note(kind, what=what)  # what siminterfaces / worlds noted when a client spawned / loaded a world
        sim.step(100)
        recorder.close()
        out = subprocess.run([*SIGCORE, "replay", str(tmp_path / name)], capture_output=True, text=True,
                             timeout=120)
        assert out.returncode == 2 and f"step 100: the run applied '{what}'" in out.stderr, out.stderr
        assert "--until 100" in out.stderr
    out = subprocess.run([*SIGCORE, "replay", str(tmp_path / "world"), "--until", "85", "--transport", "none"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "ground truth: all 6 recorded messages (steps 0 to 85) bitwise equal" in out.stdout, out.stdout
    out = subprocess.run([*SIGCORE, "replay", str(tmp_path / "world"), "--until", "150", "--transport", "none"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "the run's first world ended at step 100" in out.stderr, out.stderr

    pebble = tmp_path / "pebble.xml"
    pebble.write_text('<object shape="sphere" size="0.03" mass="0.1"/>\n')
    _spawn_and_record(tmp_path / "pebble", pebble)
    pebble.unlink()
    out = subprocess.run([*SIGCORE, "replay", str(tmp_path / "pebble"), "-q"], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 3 and "Traceback" not in out.stderr, out.stdout + out.stderr
    assert (f"the replay stopped at step 100: step 100: the spawn of uri '{pebble}' (name 'crate') is refused now "
            f"(NOT_FOUND: no file for uri '{pebble}'") in " ".join(out.stderr.split()), out.stderr
