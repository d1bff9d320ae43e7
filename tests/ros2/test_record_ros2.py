"""Recording over ROS 2 (issue 15, part 1): the simulation runs with the ROS 2 transport and --record while a
separate rclpy process steps it in lockstep and listens to /bot/joint_states and /tf (clients/record.py); the bag,
read with rosbags, holds the transport's own topics (/clock, /tf, joint states, odometry) with exactly the
messages the client received, in order, logged at their stamps."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("rclpy", reason="rclpy (ROS 2 Jazzy wheels) is not importable")
pytest.importorskip("sigcore_ros2", reason="the sigcore-ros2 plugin is not installed")

from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402
from rosproc import CLIENTS, WORLD, ros_env, start_sim  # noqa: E402

pytestmark = pytest.mark.ros2

STEP_NS = 2_000_000


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp("record_ros2")
    bag = tmp / "bag"
    sim = start_sim(tmp, WORLD, "--paused", "--record", str(bag))
    try:
        seen = sim.client("record.py", timeout=180)
        os.killpg(sim.proc.pid, signal.SIGINT)  # the run ends like Ctrl-C: the bag is closed
        try:
            sim.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            pass
        log = sim.output()
    finally:
        sim.stop()
    # raw messages read with rosbags, deserialized by rclpy: they are the rmw's own bytes, which Fast DDS may pad
    # beyond the message's end (rosbags' strict size check refuses that; ROS 2 and Foxglove readers do not)
    from rclpy.serialization import deserialize_message
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState
    from tf2_msgs.msg import TFMessage

    types = {"/clock": Clock, "/bot/joint_states": JointState, "/tf": TFMessage}  # the rest stay raw bytes
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        connections = {c.topic: c for c in reader.connections}
        messages = [(c.topic, t, deserialize_message(raw, types[c.topic]) if c.topic in types else raw)
                    for c, t, raw in reader.messages()]
    return {"seen": seen, "log": log, "connections": connections, "messages": messages, "bag": bag}


def _ns(stamp: Any) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def test_the_run_stepped_and_the_recording_completed(recorded: dict) -> None:
    """Every step_simulation call succeeded, and the reset, the spawn, the delete and set_entity_info; the run's
    report names the complete recording."""
    assert recorded["seen"]["results"] == [1] * 10 and recorded["seen"]["resets"] == [1]
    assert recorded["seen"]["changes"] == {"spawn": [1, "crate"], "delete": 1, "info": 1}
    assert "recording:" in recorded["log"] and "complete" in recorded["log"], recorded["log"][-2000:]


def test_the_transports_topics_are_recorded(recorded: dict) -> None:
    """/clock, /tf, joint states, odometry, /tf_static and readiness are in the bag with their types; /tf_static
    and /sigcore/ready are latched."""
    c = recorded["connections"]
    assert c["/clock"].msgtype == "rosgraph_msgs/msg/Clock" and c["/bot/joint_states"].msgtype == \
        "sensor_msgs/msg/JointState"
    assert c["/tf"].msgtype == "tf2_msgs/msg/TFMessage" and c["/bot/odom"].msgtype == "nav_msgs/msg/Odometry"
    for topic in ("/tf_static", "/sigcore/ready"):
        assert c[topic].ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL", topic


def test_what_the_client_received_is_what_the_bag_holds(recorded: dict) -> None:
    """The joint states the client received over DDS are exactly the bag's, in order (all 500 steps' worth at
    the state rate: 50 Hz = every 10 steps, plus one after the reset, the spawn and the delete), each logged at its
    stamp; the bag also has the one of t = 0, published before the client subscribed; so are the /tf messages'
    stamps."""
    joints = [(t, m) for topic, t, m in recorded["messages"] if topic == "/bot/joint_states"]
    assert all(t == _ns(m.header.stamp) for t, m in joints)
    bag = [t for t, _ in joints]
    got = recorded["seen"]["joints"]
    # every 10 steps from 10 to 500, and once more at the reset, the spawn and the delete (after steps 300, 350 and
    # 400: the state is published again when the entities change)
    assert got == sorted([i * 10 * STEP_NS for i in range(1, 51)] + [300 * STEP_NS, 350 * STEP_NS, 400 * STEP_NS])
    assert bag == [0, *got]  # the one at t = 0 was published at the start, before the client subscribed
    tf = [[_ns(x.header.stamp) for x in m.transforms][:1] for topic, _, m in recorded["messages"] if topic == "/tf"]
    seen = recorded["seen"]["tf"]
    assert seen and tf[len(tf) - len(seen):] == seen and tf[0] == [0]


def test_clock_is_recorded_in_order_at_simulated_times(recorded: dict) -> None:
    """/clock messages are logged at the time they carry, never going back, up to the last step (500)."""
    clocks = [(t, _ns(m.clock)) for topic, t, m in recorded["messages"] if topic == "/clock"]
    assert clocks and all(t == c for t, c in clocks)
    times = [c for _, c in clocks]
    assert times == sorted(times) and times[-1] == 500 * STEP_NS


def test_the_input_log_holds_the_clients_commands(recorded: dict) -> None:
    """/sigcore/inputs holds what the client did, at the steps it took effect: the first cmd_vel at step 0 (the
    simulation was paused there), the second at step 150, the joint command at 200, the reset at 300, the spawn at
    350, the delete and set_entity_info at 400, each with every argument a replay needs."""
    import json

    inputs = [json.loads(raw[8:-1].decode()) for topic, _, raw in recorded["messages"] if topic == "/sigcore/inputs"]
    kinds = [(i["step"], i["kind"]) for i in inputs if i["kind"] != "api" or i["args"]["entry"] == "_setJointTarget"]
    assert kinds[:4] == [(0, "base_velocity"), (150, "base_velocity"), (200, "api"), (300, "reset")]
    assert [k for k in kinds if k[1] in ("spawn", "delete", "entity_info")] == [(350, "spawn"), (400, "delete"),
                                                                                (400, "entity_info")]
    assert inputs[0]["args"] == {"robot": "bot", "linear": 0.4, "angular": 0.6}
    spawn, delete, info = [i["args"] for i in inputs if i["kind"] in ("spawn", "delete", "entity_info")]
    assert spawn == {"requests": [{"name": "crate", "uri": "", "resource": '<object shape="box" size="0.1 0.1 0.1" '
                                   'mass="1"/>', "xyz": [-0.96, 1.0, 0.3], "wxyz": [1.0, 0.0, 0.0, 0.0], "frame": "",
                                   "namespace": "", "allow_renaming": False, "tags": []}],
                     "names": ["crate"], "what": "spawn_entity crate"}
    assert delete == {"entities": ["cube"], "what": "delete_entity cube"}
    assert info == {"entity": "heavy", "category": "dynamic_object", "description": "pushed",
                    "tags": ["furniture", "moved"], "what": "set_entity_info heavy"}


def _last_truth(recorded: dict) -> Any:
    """The recording's last ground truth (a TFMessage)."""
    from rclpy.serialization import deserialize_message
    from tf2_msgs.msg import TFMessage

    raw = [m for topic, _, m in recorded["messages"] if topic == "/sigcore/ground_truth"][-1]
    return deserialize_message(raw, TFMessage)


def _replay(bag: Path, *args: str, env: dict | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", "replay", str(bag), *args], capture_output=True,
                          text=True, timeout=180, env=env)


def test_replay_reproduces_the_run_bit_for_bit(recorded: dict) -> None:
    """sigcore replay, with no client: every command applied at its step (the spawn, the delete and the entity
    information too), the poses of every frame at the end equal the recording's, bit for bit (MuJoCo); exit 0."""
    out = _replay(recorded["bag"])
    assert out.returncode == 0, out.stdout + out.stderr
    assert all(f"1 {kind}" in out.stdout for kind in ("spawn", "delete", "entity_info")), out.stdout
    assert "ground truth at step 500:" in out.stdout and "bitwise equal" in out.stdout
    frames = {tf.child_frame_id for tf in _last_truth(recorded).transforms}
    assert "ground_truth/crate" in frames and "ground_truth/cube" not in frames


def test_replay_until_a_step_hands_over_to_live_clients(recorded: dict, tmp_path: Path) -> None:
    """sigcore replay --until 255 (a ground-truth step, after the second cmd_vel): the poses there equal the
    recording's; the simulation is then paused with the ROS 2 transport up, and a client sees /clock at 0.51 s,
    not moving, and the robot where the recording has it."""
    import json

    truth = [m for topic, t, m in recorded["messages"] if topic == "/sigcore/ground_truth" and t == 255 * STEP_NS]
    assert truth
    from rclpy.serialization import deserialize_message
    from tf2_msgs.msg import TFMessage

    base = next(tf.transform.translation for tf in deserialize_message(truth[0], TFMessage).transforms
                if tf.child_frame_id == "ground_truth/bot/base_link")
    env = ros_env()
    proc = subprocess.Popen([sys.executable, "-m", "sigcore", "replay", str(recorded["bag"]), "--until", "255"],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    try:
        client = subprocess.run([sys.executable, str(CLIENTS / "replay_probe.py"), "bot"], env=env,
                                capture_output=True, text=True, timeout=120)
        lines = [line for line in client.stdout.splitlines() if line.startswith("{")]
        assert lines, client.stderr[-3000:]
        seen = json.loads(lines[-1])
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    assert "ground truth at step 255:" in out and "bitwise equal" in out, out
    assert "ready: replayed to step 255" in out
    assert seen["clocks"] and set(seen["clocks"]) == {255 * STEP_NS}
    assert seen["position"] == [base.x, base.y, base.z]


def test_a_replay_of_a_cut_recording_or_beyond_its_end_is_refused(recorded: dict, tmp_path: Path) -> None:
    """A recording without its metadata and cut: exit 2 naming the problem; --until after the end: exit 2 naming
    the last step."""
    import shutil

    out = _replay(recorded["bag"], "--until", "999999", "--transport", "none")
    assert out.returncode == 2 and "the recording ends at step 500" in out.stderr
    cut = tmp_path / "cut"
    shutil.copytree(recorded["bag"], cut)
    (cut / "metadata.yaml").unlink()
    out = _replay(cut)
    assert out.returncode == 2 and "cannot be replayed" in out.stderr and "metadata.yaml is missing" in out.stderr
    assert "Traceback" not in out.stderr
