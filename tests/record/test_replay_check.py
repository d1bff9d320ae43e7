"""What ``sigcore replay`` checks (issue 28, item 7): every recorded ground-truth frame at its step, the referee's
score, events and result message by message, and the commands a run applied after its last step.

The clean-up task with one trash item (``tests/data/eval/cleanup_one.xml``: the scripted robot puts the can in its box
at t = 31.3 s; three referee events) is recorded once by ``sigcore run --record`` (no transport); altered copies of
that recording are written with the project's own bag reader and writer (``bag_info``, ``iter_messages``,
``read_extras``, ``BagWriter``; the ground truth with the recorder's own layout), one message changed.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mcap.reader import make_reader

from sigcore.record import GROUND_TRUTH, Recorder
from sigcore.record.bag import BagWriter
from sigcore.record.bag_reading import bag_info, iter_messages, read_extras
from sigcore.record.reader import TruthReader
from sigcore.record.recorder import _TfLayout
from sigcore.record.replay import Replayer, load_recording
from sigcore.record.serialize import Serializer
from sigcore.record.verify import ReplayCheck
from sigcore.sim import Simulation, run
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[2]
SIGCORE = [sys.executable, "-m", "sigcore"]
CLEANUP = ROOT / "tests" / "data" / "eval" / "cleanup_one.xml"
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"
EVERY = 17
"""The recorder writes the ground truth every 17th step (30 Hz at 2 ms)."""

Edit = Callable[[str, int, bytes, int], bytes]
"""Changes one message: (topic, log time [ns], data, index of the message on its topic) -> new data."""


def _copy(src: Path, dst: Path, edit: Edit) -> None:
    """Write the recording ``src`` again into ``dst`` with the project's bag writer: every topic with its type,
    definition, hash and QoS, every message in log-time order (``edit`` may change its bytes), the attachments and
    the metadata records."""
    info = bag_info(src)
    with open(info.files[0], "rb") as f:
        summary = make_reader(f).get_summary()
        assert summary is not None
        schemas = {summary.schemas[c.schema_id].name: summary.schemas[c.schema_id].data.decode()
                   for c in summary.channels.values()}
    metadata, attachments = read_extras(info)
    writer = BagWriter(dst)
    topics = {t.name: writer.add_topic(t.name, t.typename, schemas[t.typename], t.digest, t.offered)
              for t in info.topics}
    for name, data in attachments.items():
        writer.attach(name, "application/octet-stream", data)
    for name, values in metadata.items():
        writer.metadata(name, values)
    seen: dict[str, int] = {}
    for topic, stamp, data in iter_messages(info):
        index = seen[topic] = seen.get(topic, -1) + 1
        target = topics[topic]
        assert target is not None
        writer.write(target, stamp, edit(topic, stamp, data, index))
    writer.close()


def _replay(path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*SIGCORE, "replay", str(path), "-q", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def task(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The one-item clean-up task run to its end by the scripted robot, recorded by ``sigcore run --record``."""
    path = tmp_path_factory.mktemp("replay") / "task"
    out = subprocess.run([*SIGCORE, "run", str(CLEANUP), "--transport", "none", "--controller",
                          "robot_000=cleanup.robot", "--duration", "300", "--record", str(path), "-q"],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    info = bag_info(path)
    counts = {t.name: t.count for t in info.topics}
    truth = [(stamp, data) for _, stamp, data in iter_messages(info, [GROUND_TRUTH])]
    return {"path": path, "frames": counts[GROUND_TRUTH], "events": counts["/referee/events"], "truth": truth,
            "final": truth[-1][0] // 2_000_000}


@pytest.mark.slow
def test_an_unaltered_recording_is_reproduced_frame_by_frame_with_the_referee(task: dict[str, Any]) -> None:
    """sigcore replay of the unaltered recording exits 0, says every recorded ground-truth frame (all of them, from
    step 0 to the last) is bitwise equal, and that the score, every event and the result were reproduced."""
    out = _replay(task["path"])
    assert out.returncode == 0, out.stdout + out.stderr
    text = " ".join(out.stdout.split())
    assert (f"ground truth: all {task['frames']} recorded messages (steps 0 to {task['final']}) bitwise equal, each "
            "at its step") in text, out.stdout
    assert re.search(rf"ground truth at step {task['final']}: \d+ frames, bitwise equal", text), out.stdout
    assert task["frames"] > task["final"] // EVERY  # every 17th step and the last
    assert "referee: score 1050 reproduced" in text, out.stdout
    assert f"referee: all {task['events']} events reproduced" in text and task["events"] == 3, out.stdout
    assert "referee: result 'succeeded', score 1050 reproduced" in text, out.stdout
    assert "DIVERGED" not in text and "NOT reproduced" not in text


@pytest.mark.slow
@pytest.mark.parametrize(("frame", "change"), [("ground_truth/can_0", "z + 5 cm"),
                                               ("ground_truth/robot_000/base_link", "x + 1 ulp")])
def test_a_pose_altered_in_the_middle_fails_the_replay_at_that_frame(task: dict[str, Any], tmp_path: Path,
                                                                     frame: str, change: str) -> None:
    """One ground-truth message in the middle of the run rewritten with one pose changed (by 5 cm, or by one unit
    in the last place): the replay exits 1 and stops there, naming that message's step, time and index, the entity,
    the difference and both poses; the frames before it are said to be reproduced."""
    index = len(task["truth"]) // 2
    stamp, data = task["truth"][index]
    poses = TruthReader(Serializer()).poses(data)
    names = list(poses)
    original = poses[frame].copy()
    altered = np.array([poses[n] for n in names])
    row = names.index(frame)
    if change == "z + 5 cm":
        altered[row, 2] += 0.05
    else:
        altered[row, 0] = np.nextafter(altered[row, 0], np.inf)
    new = _TfLayout("world", names).pack(stamp, altered)
    assert new != data and len(new) == len(data)

    def edit(topic: str, log_ns: int, message: bytes, i: int) -> bytes:
        return new if topic == GROUND_TRUTH and i == index else message

    _copy(task["path"], tmp_path / "altered", edit)
    out = _replay(tmp_path / "altered")
    assert out.returncode == 1, out.stdout + out.stderr
    text = " ".join(out.stdout.split())
    step = stamp // 2_000_000
    entity = frame.split("/")[1]
    difference = abs(altered[row] - original).max()
    assert (f"ground truth: DIVERGED at step {step} (t = {step * 0.002:.3f} s, recorded message {index}): entity "
            f"'{entity}' ({frame}) differs by {difference:.6g}") in text, out.stdout
    assert f"the {index} recorded messages before it were reproduced" in text
    assert f"replayed: {step} steps" in text, out.stdout  # it stopped at the divergence
    recorded_z = f"{altered[row, 2]:.9g}"
    assert f"recorded xyz ({altered[row, 0]:.9g}, {altered[row, 1]:.9g}, {recorded_z})" in text, out.stdout


@pytest.mark.slow
def test_a_score_altered_in_the_recording_is_reported_not_reproduced(task: dict[str, Any], tmp_path: Path) -> None:
    """The recording's last /referee/score message rewritten as 9999: the replay exits 1 saying the score was not
    reproduced, with both values and their time; the ground truth and the events are still reproduced."""
    serializer = Serializer()
    last = bag_info(task["path"])
    count = next(t.count for t in last.topics if t.name == "/referee/score")

    def edit(topic: str, log_ns: int, message: bytes, i: int) -> bytes:
        if topic == "/referee/score" and i == count - 1:
            assert serializer.deserialize("std_msgs/msg/Int32", message).data == 1050
            return serializer.serialize("std_msgs/msg/Int32", {"data": 9999})
        return message

    _copy(task["path"], tmp_path / "score", edit)
    out = _replay(tmp_path / "score")
    assert out.returncode == 1, out.stdout + out.stderr
    text = " ".join(out.stdout.split())
    assert (f"referee: score NOT reproduced (/referee/score: {count} recorded, {count} replayed): message {count} "
            "differs: recorded 9999 at t = 31.300 s, replayed 1050 at t = 31.300 s") in text, out.stdout
    assert "bitwise equal" in text and "referee: all 3 events reproduced" in text, out.stdout


def _late_command_recording(path: Path, steps: int) -> None:
    """tests/data/sim/world.xml recorded for ``steps`` steps with the wheels driven from step 10; after the last
    step the cube is moved through the API, as a ROS 2 transport applies a request still queued when it stops,
    before the recording closes."""
    from sigcore.api.call import call

    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, path)
    entries = {e.suffix: e for e in sim.api_entries()}
    sim.start()
    for step in range(steps):
        if step == 10:
            answer = call(sim, entries["_setWheelVelocity"], "bot", {"left_wheel": 3.0, "right_wheel": 1.0})
            assert isinstance(answer, dict) and answer["success"]
        sim.step()
    answer = call(sim, entries["_setPosition"], "cube", {"x": 0.3, "y": 0.2, "z": 0.9})  # after the last step
    assert isinstance(answer, dict) and answer["success"]
    sim.stop()
    recorder.close()


@pytest.mark.slow
@pytest.mark.parametrize("steps", [340, 345])
def test_a_command_applied_after_the_last_step_is_replayed_there(tmp_path: Path, steps: int) -> None:
    """A command a run applied after its last step is noted at that step and recorded; the recorder's last ground
    truth is written after it (a second message of that step when one was written there before: 340 = 20 x 17);
    a replay applies it when it stops there (every command applied, one after the last step) and reproduces every
    frame; a replay that leaves it out differs at the last frame, at the cube."""
    _late_command_recording(tmp_path / "bag", steps)
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind) for i in rec.inputs] == [(10, "api"), (steps, "api")]
    at_end = [s for s, _ in rec.truth if s == steps]
    assert len(at_end) == (2 if steps % EVERY == 0 else 1)
    assert rec.truth[-1][1]["ground_truth/cube"][:3].tolist() == [0.3, 0.2, 0.9]

    def replay(end: int | None) -> tuple[Replayer, ReplayCheck, Simulation]:
        sim = Simulation(rec.world(tmp_path / "world"), "mujoco", rec.controllers)
        replayer = Replayer(rec.inputs, end=end)
        check = ReplayCheck(rec.truth, rec.topics, steps, True, 0.0, sim.dt)
        check.attach(sim)
        run(sim, steps=steps, transport=[replayer])
        check.finish(sim)
        return replayer, check, sim

    replayer, check, sim = replay(steps)
    assert replayer.applied == 2 and replayer.after_end == 1 and replayer.pending == 0
    assert check.truth.ok and check.truth.compared == len(rec.truth) == check.truth.bitwise
    replayer, check, sim = replay(None)
    assert replayer.applied == 1 and replayer.pending == 1
    divergence = check.truth.divergence
    assert divergence is not None and divergence.step == steps and divergence.index == len(rec.truth) - 1
    assert divergence.entity == "cube" and divergence.recorded is not None
    assert list(divergence.recorded[:3]) == [0.3, 0.2, 0.9]

    out = _replay(tmp_path / "bag")
    assert out.returncode == 0, out.stdout + out.stderr
    text = " ".join(out.stdout.split())
    assert re.search(r"replayed: \d+ steps, 2 commands applied \(of 2 recorded\) \(1 of them after the last step, "
                     r"where the run applied them as it stopped\)", text), out.stdout
    assert f"ground truth: all {len(rec.truth)} recorded messages (steps 0 to {steps}) bitwise equal" in text
