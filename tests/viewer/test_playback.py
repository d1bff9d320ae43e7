"""``sigcore view DIR``: the web viewer plays a recording back (``WebViewer.play_recording``).

A real recording of the clean-up task (``sigcore run ... --record``, 40 s: robot_000 grasps can_0 at 12.5 s and puts
it in trashbox_2 at 31.3 s) is shown by a real viewer: ``sigcore view DIR`` as a subprocess, or the viewer in this
process (so that ``WebViewer.node_pose`` reads what viser holds for a scene node), with its own viewer process and viser
server, opened in a real headless Chromium (``sigcore_viewer.browser``: selenium with Debian's chromium and
chromium-driver) and driven like a person would. Without a browser: the ground truth and texts as read from the bag
against what the recorder wrote and what the live viewer showed, a cut recording, and the refusals of the command line.
Chromium renders WebGL in software here: while the scene moves, each selenium call can take seconds, so the tests
keep the playback paused while they look and wait with bounded polls.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from pages import PAGE_FPS
from sigcore_viewer import commands, playback
from sigcore_viewer.browser import Browser, missing
from sigcore_viewer.overlays import OVERLAYS
from sigcore_viewer.snapshot import Pushed, Snapshot
from sigcore_viewer.viewer import WebViewer

from sigcore.geometry import quat_to_matrix
from sigcore.record import Recorder
from sigcore.record.recorder import truth_frame
from sigcore.record.replay import load_recording
from sigcore.sim import Simulation, run
from sigcore.world import parse_world

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
SIGCORE = [sys.executable, "-m", "sigcore"]
DT_NS = 2_000_000
"""The clean-up world's timestep [ns]."""
GRASP = "robot_000 grasped can_0"
"""The referee's first event, at 12.5 s."""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """40 s of the clean-up task recorded by the command line (about 5 s)."""
    path = tmp_path_factory.mktemp("playback") / "cleanup40"
    done = subprocess.run([*SIGCORE, "run", str(CLEANUP), "--transport", "none", "--controller",
                           "robot_000=cleanup.robot", "--duration", "40", "--record", str(path), "-q"],
                          capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "complete" in done.stdout and GRASP in done.stdout, done.stdout
    return path


@pytest.fixture
def browser_ready() -> None:
    if os.environ.get("SIGCORE_NO_BROWSER"):
        pytest.skip("SIGCORE_NO_BROWSER is set: the viewer's browser tests are skipped")
    if missing() is not None:  # scripts/setup.sh installs them as root: a missing browser is a failed set-up
        raise RuntimeError(f"the viewer's browser tests cannot run: {missing()}")


def truth_at(path: Path, t: float) -> dict[str, np.ndarray]:
    """The recorded ground truth at or before ``t`` [s] (read with the core's replay reader)."""
    truth = load_recording(path).truth
    step = round(t * 1e9) // DT_NS
    return [poses for at, poses in truth if at <= step][-1]


def shown_time(page: Browser) -> float | None:
    """The simulated time the page's status line shows."""
    found = re.search(r"t = ([0-9.]+) s of", page.text())
    return float(found.group(1)) if found else None


def scrub(page: Browser, t: float) -> None:
    """Type ``t`` in the time slider's box, as a person would, and wait until the page shows that moment."""
    page.type("Time [s]", f"{t:g}")
    page.wait(lambda p: f"t = {t:.2f} s of" in p.text(), 30, f"the page shows t = {t:.2f} s")


class View:
    """``sigcore view DIR`` in a process of its own (its own process group): its stderr lines, its page."""

    def __init__(self, path: Path) -> None:
        self.port = free_port()
        self.proc = subprocess.Popen([*SIGCORE, "view", str(path), "--viewer-port", str(self.port)], cwd=ROOT,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     start_new_session=True)
        self.lines: list[str] = []
        assert self.proc.stderr is not None
        threading.Thread(target=lambda: self.lines.extend(self.proc.stderr), daemon=True).start()  # type: ignore
        deadline = time.monotonic() + 60
        while not any("ready:" in line for line in self.lines):
            assert self.proc.poll() is None and time.monotonic() < deadline, "".join(self.lines)
            time.sleep(0.05)
        self.url = f"http://127.0.0.1:{self.port}"

    def end(self) -> int:
        """Ctrl-C (SIGINT to its process group, as a terminal sends it); killed if it does not end."""
        try:
            os.killpg(self.proc.pid, signal.SIGINT)
            return self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            return -1
        finally:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()


@pytest.fixture
def view(recording: Path, browser_ready: None) -> Iterator[View]:
    shown = View(recording)
    try:
        yield shown
    finally:
        code = shown.end()
        assert code == 0, "".join(shown.lines)
        assert "Traceback" not in "".join(shown.lines)


# ---------------------------------------------------------------------- in a browser
@pytest.mark.slow
@pytest.mark.browser
def test_the_panel_is_a_player_and_scrubbing_shows_the_texts_of_that_moment(view: View) -> None:
    """The panel is a player: a time slider over the 40 s, play and pause, speeds, to start and to end; step, reset,
    the pace and messages are gone, dragging is disabled. Scrubbing shows the score and events of that moment: the
    grasp at 12.5 s and not at 12.4 s; To end shows the can in its box, To start no events."""
    with Browser(view.url, max_fps=PAGE_FPS) as page:
        page.wait(lambda p: "Time [s]" in p.text() and "To end" in p.text(), 60, "the page shows the timeline")
        text = page.text()
        assert "Playback" in text and "Speed" in text and "To start" in text and "Recording" in text
        assert "t = 0.00 s of 0.00–40.00 s" in text and "paused ·" in text
        for live in ("Steps", "Reset", "Pace", "Send", "Message"):  # the live run's controls are not shown
            assert live not in text.split("\n"), text
        assert "dragging belong to live runs" in text
        assert page.field("Drag handle").get_attribute("disabled") is not None

        scrub(page, 12.4)
        text = page.text()
        assert "score: 0" in text and "no events yet" in text and GRASP not in text
        scrub(page, 12.5)
        text = page.text()
        assert "score: 50" in text and re.search(r"12\.50 s\s+\+50\s+robot_000 grasped can_0", text), text
        assert "in trashbox_2" not in text

        page.click("To end")
        page.wait(lambda p: "t = 40.00 s of" in p.text(), 30, "To end shows the last moment")
        text = page.text()
        assert "score: 1050" in text and "can_0 in trashbox_2" in text and GRASP in text
        assert "paused at the end" in text
        page.click("To start")
        page.wait(lambda p: "t = 0.00 s of" in p.text(), 30, "To start shows the first moment")
        assert "no events yet" in page.text() and "score: 0" in page.text()


@pytest.mark.slow
@pytest.mark.browser
def test_two_browsers_share_the_playback_and_play_advances_the_time(view: View) -> None:
    """A second browser sees the moment the first one scrubbed to; the first one closing changes nothing; in the
    second, Play at 10x plays to the end and stops there (at 1x that would take 27 s, more than the 20 s allowed),
    and Play then Pause from the start advances the time shown and holds it."""
    first = Browser(view.url, max_fps=PAGE_FPS)
    try:
        first.wait(lambda p: "Time [s]" in p.text(), 60, "the page shows the timeline")
        with Browser(view.url, max_fps=PAGE_FPS) as second:
            second.wait(lambda p: "Time [s]" in p.text(), 60, "a second page shows the timeline")
            scrub(first, 12.5)
            second.wait(lambda p: "t = 12.50 s of" in p.text() and GRASP in p.text(), 30,
                        "the second browser shows the moment the first one scrubbed to")
            first.close()  # a browser that goes away changes nothing
            second.pick("Speed", "10x")
            second.click("Play")
            second.wait(lambda p: "paused at the end" in p.text(), 20, "10x plays to the end and stops")
            assert "t = 40.00 s of" in second.text()
            second.click("To start")
            second.wait(lambda p: "t = 0.00 s of" in p.text(), 30, "To start shows the first moment")
            second.pick("Speed", "1x")
            second.click("Play")
            second.wait(lambda p: (shown_time(p) or 0.0) > 0.0, 30, "Play advances the time shown")
            second.click("Pause")  # only once the time moved: a Pause that overtakes the first frame holds t = 0
            second.wait(lambda p: "paused ·" in p.text(), 30, "Pause holds the time shown")
            paused = shown_time(second)
            time.sleep(1.0)
            assert shown_time(second) == paused and paused is not None and paused < 40.0
    finally:
        first.close()


@pytest.mark.slow
@pytest.mark.browser
def test_scrubbing_puts_each_node_where_the_ground_truth_has_it(recording: Path, browser_ready: None) -> None:
    """The viewer plays in this process (its viewer process and viser server its own), a browser scrubs: at t = 0 and
    t = 30 s robot_000's base node, can_0's node and the left hand (composed from its node under the base) are where
    the recorded ground truth has them, within 1e-6 m; they moved in between."""
    viewer = WebViewer(port=free_port())
    pushed: list[Pushed] = []
    taken: list[Snapshot] = []
    viewer.push_observers.append(pushed.append)
    viewer.snapshot_observers.append(taken.append)
    stop = threading.Event()
    failure: list[BaseException] = []

    def play() -> None:
        try:
            viewer.play_recording(recording, stop.is_set)
        except BaseException as e:  # the test fails with it below
            failure.append(e)

    viewer.open()
    player = threading.Thread(target=play, name="playback")
    player.start()
    try:
        with Browser(viewer.url, max_fps=PAGE_FPS) as page:
            page.wait(lambda p: "Time [s]" in p.text(), 60, "the page shows the timeline")
            layout = next(s.layout for s in taken if s.layout is not None and s.layout.frames)
            base = layout.parts.index(("robot_000", None))
            can = layout.parts.index(("can_0", None))
            hand = layout.parts.index(("robot_000", "l_hand_link"))
            assert layout.parent[hand] == base
            seen = {}
            for t in (30.0, 0.0):
                scrub(page, t)
                step = round(t * 1e9) // DT_NS
                deadline = time.monotonic() + 10
                while not any(r.step == step for r in pushed):  # the snapshot of that moment was handed to viser
                    assert time.monotonic() < deadline, f"no snapshot of step {step} was pushed"
                    time.sleep(0.05)
                assert next(s for s in reversed(taken) if s.step == step).exact  # paused: every frame sent as is
                truth = truth_at(recording, t)
                got = {}
                for index, name in ((base, "ground_truth/robot_000/base_link"), (can, "ground_truth/can_0")):
                    node = viewer.node_pose(f"/sigcore/f{index}")
                    assert node is not None
                    got[name] = np.concatenate(node)
                    np.testing.assert_allclose(got[name][:3], truth[name][:3], atol=1e-6)
                    np.testing.assert_allclose(got[name][3:], truth[name][3:], atol=1e-6)
                link = viewer.node_pose(f"/sigcore/f{base}/l{hand}")  # relative to the base's node
                assert link is not None
                root = got["ground_truth/robot_000/base_link"]
                position = root[:3] + quat_to_matrix(root[3:]) @ np.array(link[0])
                np.testing.assert_allclose(position, truth["ground_truth/robot_000/l_hand_link"][:3], atol=1e-6)
                seen[t] = got
            for name in ("ground_truth/robot_000/base_link", "ground_truth/can_0"):
                assert np.linalg.norm(seen[30.0][name][:3] - seen[0.0][name][:3]) > 0.3, name
    finally:
        stop.set()
        player.join(timeout=30)
        viewer.stop()
    assert not player.is_alive() and not failure, failure


# ---------------------------------------------------------------------- without a browser
@pytest.mark.slow
def test_the_texts_are_those_the_live_viewer_showed(tmp_path: Path) -> None:
    """A run recorded while a live viewer showed it, reset at 20 s (after the first grasp): at the moment of every
    snapshot the live viewer took, the playback's score, events and result are the same texts (the reset cleared the
    events in both; at the reset's own moment the playback shows it done, so that snapshot is left out)."""
    sim = Simulation(parse_world(CLEANUP), "mujoco", controllers={"robot_000": "cleanup.robot"})
    recorder = Recorder(sim, tmp_path / "live")
    viewer = WebViewer(port=free_port())
    live: list[tuple[int, dict[str, str]]] = []
    viewer.snapshot_observers.append(lambda s: live.append((s.step, dict(s.texts))))

    def reset_at_20_s(s: Simulation) -> None:
        if s.worlds.elapsed_steps == 10_000:
            viewer._post(commands.reset)  # as the panel's Reset does

    sim.events.subscribe("step", reset_at_20_s)
    try:
        report = run(sim, duration=40.0, transport=[viewer], realtime_factor=None, handle_signals=False)
    finally:
        recorder.close()
        viewer.stop()
    assert report.error is None
    recorded = playback.load(tmp_path / "live", tmp_path / "work")
    assert len(recorded.lines.resets) == 1
    reset_step = recorded.lines.resets[0][0] // DT_NS
    compared = 0
    for step, texts in live:
        if step == reset_step:
            continue
        again = recorded.lines.at(step * DT_NS)
        assert {k: texts[k] for k in again} == again, f"at step {step}"
        compared += 1
    assert compared > 30
    assert any(GRASP in texts["events"] for step, texts in live if step < reset_step)  # the grasp, then
    assert any(texts["events"] == "no events yet" for step, texts in live if step > reset_step)  # cleared


@pytest.mark.slow
def test_the_ground_truth_is_read_exactly_and_a_cut_recording_up_to_its_cut(recording: Path,
                                                                             tmp_path: Path) -> None:
    """Every frame's pose at every ground-truth message is bit for bit what the recorder wrote (as the core's replay
    reads it); a recording killed mid-way (no metadata.yaml, its file cut) is shown up to where it is readable, and
    the panel's note says it is cut."""
    whole = playback.load(recording, tmp_path / "w1")
    truth = load_recording(recording).truth
    assert [int(t) for t in whole.times] == [step * DT_NS for step, _ in truth]
    linked = {"robot_000", "man_0"}  # the entities with link frames: the robot and the person
    names = [truth_frame(entity, frame, entity in linked)
             for (entity, _), frame in zip(whole.layout.parts, whole.layout.frames, strict=True)]
    assert "ground_truth/man_0/head_man_0" in names and "ground_truth/man_0" in names
    for k, (_, poses) in enumerate(truth):
        assert np.array_equal(whole.poses[k], np.stack([poses[n] for n in names])), k
    assert whole.tracked.all() and not whole.untracked and not whole.problems
    assert (whole.start_ns, whole.end_ns) == (0, 40 * 10**9)
    player = playback.Player(whole, dict(OVERLAYS))
    assert "cut" not in player.timeline().note

    cut = tmp_path / "cut"
    shutil.copytree(recording, cut)
    (cut / "metadata.yaml").unlink()
    mcap = next(cut.glob("*.mcap"))
    with open(mcap, "r+b") as f:
        f.truncate(mcap.stat().st_size // 2 + 3)
    part = playback.load(cut, tmp_path / "w2")
    assert part.problems and 0 < len(part.times) < len(whole.times)
    assert np.array_equal(part.times, whole.times[:len(part.times)])
    assert np.array_equal(part.poses, whole.poses[:len(part.times)])
    assert part.end_ns < whole.end_ns
    assert "The recording is cut" in playback.Player(part, dict(OVERLAYS)).timeline().note


def test_an_entity_deleted_while_running_is_hidden_from_then_on(tmp_path: Path) -> None:
    """can_0 deleted at 1 s of a recorded run: before, its node is where the ground truth has it and shown; from the
    ground truth after the deletion on, it is hidden (and the panel's selection says it is not in the world); the other
    entities stay shown."""
    sim = Simulation(parse_world(CLEANUP), "mujoco")
    recorder = Recorder(sim, tmp_path / "deleted")
    try:
        sim.step(500)
        sim.entities.delete(["can_0"])
        sim.step(500)
    finally:
        recorder.close()
    recorded = playback.load(tmp_path / "deleted", tmp_path / "work")
    can = recorded.layout.parts.index(("can_0", None))
    truth = truth_at(tmp_path / "deleted", 0.9)
    poses, hidden = recorded.poses_at(round(0.9e9))
    assert not hidden.any()
    assert np.array_equal(poses[can], truth["ground_truth/can_0"])
    poses, hidden = recorded.poses_at(round(1.5e9))
    assert hidden[can] and hidden.sum() == 1
    player = playback.Player(recorded, dict(OVERLAYS))
    player.request(("select", "can_0"), 0.0)
    player.request(("seek", 1.5), 0.0)
    snap = player.snapshot(0.0)
    assert snap.hidden is not None and snap.hidden[can] and snap.exact
    assert "not in the world at t = 1.50 s" in snap.texts["selection"]


def _rewrite(source: Path, target: Path, attachments: bool = True, truth: bool = True) -> None:
    """``source``'s MCAP file written again to ``target`` without its attachments or its ground truth."""
    from mcap.reader import make_reader
    from mcap.writer import Writer

    with open(next(source.glob("*.mcap")), "rb") as f, open(target, "wb") as out:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        writer = Writer(out)
        writer.start(profile="ros2", library="test")
        schemas = {sid: writer.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        channels = {cid: writer.register_channel(c.topic, c.message_encoding, schemas[c.schema_id], c.metadata)
                    for cid, c in summary.channels.items()}
        for meta in reader.iter_metadata():
            writer.add_metadata(meta.name, meta.metadata)
        if attachments:
            for item in reader.iter_attachments():
                writer.add_attachment(item.create_time, item.log_time, item.name, item.media_type, item.data)
        for _, channel, message in reader.iter_messages():
            if truth or channel.topic != "/sigcore/ground_truth":
                writer.add_message(channels[channel.id], message.log_time, message.data, message.publish_time)
        writer.finish()


def _view(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*SIGCORE, "view", str(path), "--viewer-port", str(free_port())], capture_output=True,
                          text=True, cwd=ROOT, timeout=60, start_new_session=True)


@pytest.mark.slow
def test_a_recording_that_cannot_be_shown_is_refused_naming_what_is_missing(recording: Path,
                                                                             tmp_path: Path) -> None:
    """``sigcore view`` of a directory that holds no recording, of a recording without its attachments (the world
    cannot be rebuilt) and of one without ground truth: exit 2, one line naming the file and what is missing."""
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("no recording here\n")
    bare = tmp_path / "bare.mcap"
    _rewrite(recording, bare, attachments=False)
    blind = tmp_path / "blind.mcap"
    _rewrite(recording, blind, truth=False)
    for target, says in ((foreign, f"{foreign} holds no .mcap file"),
                         (bare, f"{bare}: the world file is not attached (world/cleanup.xml); attachments: none"),
                         (blind, f"{blind} holds no ground truth (no message on /sigcore/ground_truth)")):
        done = _view(target)
        assert done.returncode == 2, done.stdout + done.stderr
        assert says in done.stderr and "Traceback" not in done.stderr, done.stderr
        assert done.stderr.count("sigcore view:") == 1, done.stderr


def test_an_entity_spawned_while_running_is_drawn_from_then_on(tmp_path: Path) -> None:
    """A crate spawned at 1 s (noted in the input log as the ROS 2 transport notes it): the playback's scene has
    it, hidden before its spawn and shown where the ground truth has it after; nothing is listed as not drawn."""
    from sigcore.world.resources import SpawnRequest

    sim = Simulation(parse_world(CLEANUP), "mujoco")
    recorder = Recorder(sim, tmp_path / "spawned")
    try:
        sim.step(500)
        requests = [SpawnRequest(name="crate", resource='<object name="x" shape="box" size="0.2 0.2 0.2" mass="1"/>',
                                 xyz=(0.0, 1.0, 0.5))]
        sim.inputs.note_spawn(requests, sim.entities.spawn(requests))
        sim.step(500)
    finally:
        recorder.close()
    recorded = playback.load(tmp_path / "spawned", tmp_path / "work")
    assert recorded.untracked == []
    crate = recorded.layout.parts.index(("crate", None))
    poses, hidden = recorded.poses_at(round(0.9e9))
    assert hidden[crate] and hidden.sum() == 1
    poses, hidden = recorded.poses_at(round(1.9e9))
    assert not hidden.any()
    assert np.array_equal(poses[crate], truth_at(tmp_path / "spawned", 1.9)["ground_truth/crate"])
    assert poses[crate][2] < 0.2  # it fell from 0.5 m onto the floor
