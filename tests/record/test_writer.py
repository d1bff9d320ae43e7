"""The recording's writer process (sigcore/record/_writer.py): the MCAP file is built in a process of its own; a run
killed mid-way still leaves a complete bag; a writer that dies stops the recording, never the run."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from sigcore.record import Recorder
from sigcore.record.bag_reading import bag_info, iter_messages
from sigcore.sim import Simulation
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[2]
WORLD = ROOT / "tests" / "data" / "sim" / "world.xml"
CLEANUP = ROOT / "worlds" / "cleanup.xml"


def test_the_file_is_written_by_another_process_and_holds_every_message(tmp_path: Path) -> None:
    """The writer is a child process, not this one; after the close, the bag holds exactly the messages handed
    over, per topic (the ground truth at its rate and the last step's), and the child has ended."""
    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    proc = recorder.bag._proc
    assert proc.pid != os.getpid() and proc.poll() is None
    sim.start()
    sim.step(600)
    recorder.close()  # it hands over the last step's ground truth, then closes
    handed = {name: t.count for name, t in recorder.bag.topics.items()}
    assert proc.poll() == 0
    info = bag_info(tmp_path / "bag")
    assert info.problems == []
    assert {t.name: t.count for t in info.topics} == handed
    assert recorder.messages == sum(handed.values()) == info.messages > 0


@pytest.mark.slow
def test_a_run_killed_mid_way_leaves_a_complete_bag(tmp_path: Path) -> None:
    """sigcore run --record killed with SIGKILL (no chance to close anything): the writer process sees its input
    end and closes the recording itself: metadata.yaml is written, the file has its summary, and it holds the
    ground truth up to shortly before the kill."""
    bag = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "sigcore", "run", str(CLEANUP), "--transport", "none",
                             "--controller", "robot_000=cleanup.robot", "--duration", "600", "--record", str(bag)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and not list(bag.glob("*.mcap")):
            time.sleep(0.2)
        time.sleep(3.0)  # some seconds of the run recorded
        assert proc.poll() is None, proc.stdout.read() if proc.stdout else ""
    finally:
        proc.kill()
        proc.wait(30)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (bag / "metadata.yaml").exists():
        time.sleep(0.2)
    info = bag_info(bag)
    assert info.problems == [], info.problems
    truth = [t for topic, t, _ in iter_messages(info, ["/sigcore/ground_truth"])]
    assert len(truth) > 30 and truth == sorted(truth)
    assert info.messages == sum(t.count for t in info.topics)


def test_a_writer_that_dies_stops_the_recording_not_the_run(tmp_path: Path) -> None:
    """The writer process killed during a run: the simulation steps on, the recorder says the writer ended
    (naming it), writes nothing more, and the close neither hangs nor raises; bag info reports the cut file, not a
    traceback."""
    sim = Simulation(parse_world(WORLD), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    sim.start()
    sim.step(300)
    os.kill(recorder.bag._proc.pid, signal.SIGKILL)
    recorder.bag._proc.wait(10)
    sim.step(1000)  # queued messages now fail to go: the recording stops, the run does not
    assert sim.step_count == 1300
    t0 = time.monotonic()
    recorder.close()
    assert time.monotonic() - t0 < 10
    failure = recorder.bag.failure
    assert failure is not None and "writer process ended unexpectedly" in failure and "the run goes on" in failure
    assert not recorder.bag.active
    info = bag_info(tmp_path / "bag")
    assert info.problems and "metadata.yaml" in " ".join(info.problems)


def test_a_world_with_files_outside_its_folder_is_rebuilt_from_the_attachments(tmp_path: Path) -> None:
    """A world whose URDF and mesh sit beside its folder (``../models/``): the world file, the URDF and the mesh
    are attached at their places under one folder; with the originals gone, the recording's world is rebuilt from
    the attachments and simulates, and replaying it gives the recorded poses bit for bit."""
    from sigcore.record.replay import compare, load_recording, poses_now

    src = tmp_path / "src"
    (src / "worlds").mkdir(parents=True)
    (src / "models").mkdir()
    shutil.copy(WORLD.parent / "minibot.urdf", src / "models" / "minibot.urdf")
    shutil.copy(ROOT / "tests" / "data" / "worlds" / "models" / "mug.obj", src / "models" / "mug.obj")
    text = WORLD.read_text().replace('urdf="minibot.urdf"', 'urdf="../models/minibot.urdf"')
    text = text.replace("</world>", '  <object name="mug" mesh="../models/mug.obj" mass="0.3" pose="0.5 -0.8 0.2"/>\n'
                                    "</world>")
    (src / "worlds" / "meshy.xml").write_text(text)
    sim = Simulation(parse_world(src / "worlds" / "meshy.xml"), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    sim.start()
    sim.step(400)
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert set(rec.attachments) == {"world/worlds/meshy.xml", "world/models/minibot.urdf", "world/models/mug.obj"}
    assert rec.attachments["world/models/mug.obj"] == (src / "models" / "mug.obj").read_bytes()
    shutil.rmtree(src)
    world = rec.world(tmp_path / "work")
    assert Path(world.source) == tmp_path / "work" / "world" / "worlds" / "meshy.xml"
    again = Simulation(world, "mujoco", rec.controllers)
    again.start()
    again.step(rec.final_step)
    equal, worst, where = compare(rec.truth[-1][1], poses_now(again))
    assert equal and worst == 0.0, (worst, where)
