"""The web viewer in-process, without a browser: a person's commands, the snapshots it pushes, its port, a run.

Each test starts a real :class:`WebViewer` (a viser server on a free port) on a real MuJoCo simulation and drives it
in lockstep from the test thread, which plays the simulation thread: it services the viewer and steps, as the loop
of :func:`sigcore.sim.run` does. Commands are queued (``_post``) and run at the next service; the snapshots taken are
read through ``snapshot_observers``, the viewer's process reports each one it handed to viser (``push_observers``),
and what viser holds for a scene node there is asked with ``node_pose``.
"""

from __future__ import annotations

import math
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from sigcore_viewer import commands
from sigcore_viewer.scenebuild import SceneLayout
from sigcore_viewer.snapshot import Pushed, Snapshot
from sigcore_viewer.viewer import WebViewer

from sigcore.agent.events import Message
from sigcore.errors import ViewerError
from sigcore.publish import Publication
from sigcore.sim import Simulation, run
from sigcore.viewer import DEFAULT_PORT, VIEWER_SENDER
from sigcore.world import World, parse_world

ROOT = Path(__file__).resolve().parents[2]
CLEANUP = ROOT / "worlds" / "cleanup.xml"
TIMEOUT = 10.0
"""Wall seconds a snapshot may take to be taken and pushed (it takes milliseconds; generous for a loaded CI)."""


def free_port() -> int:
    """A port the OS says is free now (outside 8080..8179, where a viewer started with port=None looks)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def port_of(viewer: WebViewer) -> int:
    """The port in the viewer's URL."""
    return int(viewer.url.rsplit(":", 1)[1])


class Lockstep:
    """A started viewer on ``sim``, driven from the test thread, the snapshots it took and the reports of those its
    process pushed.

    Args:
        sim: The simulation.
        viewer: The viewer, open; started on ``sim`` here, once it is watched.
    """

    def __init__(self, sim: Simulation, viewer: WebViewer) -> None:
        self.sim = sim
        self.viewer = viewer
        self.taken: list[Snapshot] = []
        self.reports: list[Pushed] = []
        viewer.snapshot_observers.append(self.taken.append)
        viewer.push_observers.append(self.reports.append)
        viewer.start(sim)

    def tick(self) -> bool:
        """One pass of the run loop: service the viewer (its commands call the run control's verbs), step unless
        paused with nothing pending.

        Returns:
            Whether the simulation stepped.
        """
        self.viewer.service(0.0)
        if not self.sim.control.take_step():
            return False
        self.sim.step()
        return True

    def show(self) -> Snapshot:
        """Service the viewer (no step) until it takes a snapshot and its process has pushed it (or a later one: it
        skips those it had no time for); return the newest snapshot pushed."""
        since = time.perf_counter()
        deadline = since + TIMEOUT
        while time.perf_counter() < deadline:
            self.viewer.service(0.0)
            if self.reports and self.reports[-1].taken >= since:
                return next(s for s in reversed(self.taken) if s.wall == self.reports[-1].taken)
            time.sleep(0.002)
        pytest.fail(f"no snapshot was pushed within {TIMEOUT} s")

    def run(self, command: commands.Command) -> Snapshot:
        """Queue ``command`` as the panel does; the snapshot that shows its effect (a command forces one)."""
        self.viewer._post(command)
        return self.show()

    def layout(self) -> SceneLayout:
        """The newest layout sent (the first snapshot always carries one)."""
        return next(s.layout for s in reversed(self.taken) if s.layout is not None)


def newest_note(snap: Snapshot) -> str:
    """The newest note of ``snap`` without its ``t = ... s:`` stamp (notes are shown newest first)."""
    first = snap.texts["notes"].split("  \n")[0]
    stamp, _, text = first.partition(": ")
    assert stamp.startswith("t = "), first
    return text


@pytest.fixture(scope="module")
def cleanup_world() -> World:
    """The clean-up world (robot_000, static tables, can_0 on table_0, the referee), parsed once."""
    return parse_world(CLEANUP)


@pytest.fixture
def cleanup(cleanup_world: World) -> Simulation:
    """A fresh simulation of the clean-up world on MuJoCo."""
    return Simulation(cleanup_world, "mujoco")


@pytest.fixture
def viewers() -> Iterator[Callable[..., WebViewer]]:
    """Makes viewers; every one made is stopped at the end of the test, however it ends."""
    made: list[WebViewer] = []

    def make(port: int | None, rate: float = 30.0) -> WebViewer:
        viewer = WebViewer(port=port, rate=rate)
        made.append(viewer)
        return viewer

    yield make
    for viewer in made:
        viewer.stop()


@pytest.fixture
def lockstep(viewers: Callable[..., WebViewer]) -> Callable[[Simulation], Lockstep]:
    """Starts a viewer on a free port on a simulation and returns its lockstep driver."""
    def start(sim: Simulation) -> Lockstep:
        viewer = viewers(free_port())
        viewer.open()
        return Lockstep(sim, viewer)
    return start


# ------------------------------------------------------------------ the run's controls
@pytest.mark.slow
def test_pause_step_n_and_play(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """Pause holds the simulation; step(5) queues exactly 5 steps; a bad count is a note naming 1..100000 that
    changes nothing; play runs on."""
    lock = lockstep(cleanup)
    control = cleanup.control
    snap = lock.run(commands.pause)
    assert control.paused and snap.status.startswith("**paused**")
    assert not lock.tick()
    lock.run(commands.step(5))
    assert (control.paused, control.pending_steps) == (True, 5)
    for bad, shown in (("abc", "'abc'"), (0, "0"), (10**6, "1000000")):
        snap = lock.run(commands.step(bad))
        assert newest_note(snap) == f"steps must be a whole number from 1 to 100000, got {shown}"
        assert (control.paused, control.pending_steps) == (True, 5)
    before = cleanup.worlds.elapsed_steps
    assert [lock.tick() for _ in range(7)] == [True] * 5 + [False] * 2
    assert cleanup.worlds.elapsed_steps == before + 5
    snap = lock.run(commands.play)
    assert not control.paused and snap.status.startswith("**running")
    assert lock.tick() and lock.tick()


@pytest.mark.slow
def test_pace(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """A pace sets control.realtime_factor (2x: 2.0; as fast as possible: None); an unknown one is a note listing
    every valid pace and changes nothing."""
    lock = lockstep(cleanup)
    control = cleanup.control
    snap = lock.run(commands.set_pace("2x"))
    assert control.realtime_factor == 2.0 and "running (2x)" in snap.status
    lock.run(commands.set_pace("as fast as possible"))
    assert control.realtime_factor is None
    snap = lock.run(commands.set_pace("3x"))
    assert control.realtime_factor is None
    note = newest_note(snap)
    assert note.startswith("unknown pace '3x'; valid: ")
    assert all(name in note for name in commands.PACES)


# ------------------------------------------------------------------ messages
@pytest.mark.slow
def test_message_reaches_the_agent(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """A message from the viewer reaches the agent before the next step, sent by "viewer"; one to a missing agent
    or with no text is a note, nothing is delivered, and the simulation steps on."""
    lock = lockstep(cleanup)
    received: list[Message] = []
    cleanup.events.subscribe("message", received.append)
    snap = lock.run(commands.send_message("robot_000", "hello"))
    assert newest_note(snap) == "sent to robot_000: hello"
    assert received == []  # queued: delivered before the next step
    assert lock.tick()
    assert [(m.sender, m.to, m.content) for m in received] == [(VIEWER_SENDER, "robot_000", "hello")]
    assert VIEWER_SENDER == "viewer"

    snap = lock.run(commands.send_message("ghost", "hello"))
    note = newest_note(snap)
    assert note.startswith("agent 'ghost' no longer exists: the message was not sent; agents: ")
    assert all(name in note for name in cleanup.entities)
    snap = lock.run(commands.send_message("robot_000", "   "))
    assert newest_note(snap) == "type a message first"
    before = cleanup.worlds.elapsed_steps
    assert lock.tick() and lock.tick()
    assert cleanup.worlds.elapsed_steps == before + 2
    assert len(received) == 1


# ------------------------------------------------------------------ moving and resetting
@pytest.mark.slow
def test_move_entity(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """Dragging can_0 teleports it at once (pose read back before any step, in the snapshot and in viser's scene
    node of its frame); table_0 is static: a note says so and its pose is unchanged."""
    lock = lockstep(cleanup)
    target, wxyz = np.array([-1.0, 0.3, 0.5]), np.array([math.cos(0.3), 0.0, 0.0, math.sin(0.3)])
    steps = cleanup.worlds.elapsed_steps
    snap = lock.run(commands.move_entity("can_0", target, wxyz))
    assert cleanup.worlds.elapsed_steps == steps
    pos, quat = cleanup.backend.get_pose("can_0")
    np.testing.assert_allclose(pos, target, atol=1e-6)
    np.testing.assert_allclose(quat, wxyz, atol=1e-6)
    index = lock.layout().parts.index(("can_0", None))
    np.testing.assert_allclose(snap.poses[index], np.concatenate([target, wxyz]), atol=1e-6)
    node = lock.viewer.node_pose(f"/sigcore/f{index}")  # what viser sends the browsers, in the viewer's process
    assert node is not None
    np.testing.assert_allclose(np.concatenate(node), np.concatenate([target, wxyz]), atol=1e-6)

    table_pos, table_quat = (np.array(a) for a in cleanup.backend.get_pose("table_0"))
    snap = lock.run(commands.move_entity("table_0", target, wxyz))
    assert newest_note(snap).startswith("table_0 is static (fixed in place): it cannot be dragged")
    pos, quat = cleanup.backend.get_pose("table_0")
    assert np.array_equal(pos, table_pos) and np.array_equal(quat, table_quat)


@pytest.mark.slow
def test_reset_during_a_grasp(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """Reset while robot_000 holds can_0: the note names the released object; the reset is done when the command
    runs (between steps, as simulation_interfaces' reset): the grasp is gone, the can is back where it started and
    the page no longer shows the old trial's events."""
    lock = lockstep(cleanup)
    start = np.array(cleanup.backend.get_pose("can_0")[0])
    robot = cleanup.robot("robot_000")
    cleanup.entities["can_0"].set_position(robot.part_position("l_hand_link"))
    robot.grasp("l_hand_link", "can_0")
    assert lock.tick()
    assert cleanup.entities.grasps.items() == [("robot_000", "l_hand_link", "can_0")]
    for _ in range(500):  # the referee scores the grasp within its check period (deterministic: in steps)
        if "robot_000 grasped can_0" in lock.show().texts["events"]:
            break
        assert lock.tick()
    assert "robot_000 grasped can_0" in lock.show().texts["events"]
    snap = lock.run(commands.reset)
    assert newest_note(snap) == "reset to the start: robot_000 let go of can_0"
    assert cleanup.entities.grasps.items() == []
    np.testing.assert_allclose(cleanup.backend.get_pose("can_0")[0], start, atol=1e-3)
    assert lock.tick()
    after = lock.show()  # the old trial's events are gone with it (the reset event); the score is the new one's
    assert after.texts["events"] == "no events yet" and after.texts["score"] == "score: 0"


# ------------------------------------------------------------------ what is shown
def test_snapshot_shows_every_entity_the_status_and_the_score(
        cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """The first pushed snapshot carries a layout with a root frame per entity; poses are finite unit-quaternion
    poses equal to the backend's; the status names the world and the step; the referee's score reads "score: 0"."""
    lock = lockstep(cleanup)
    for _ in range(10):
        assert lock.tick()
    snap = lock.show()
    layout = lock.taken[0].layout
    assert layout is not None
    assert [entity for entity, part in layout.parts if part is None] == list(cleanup.entities.names)
    assert len(set(layout.frames)) == len(layout.frames) == snap.poses.shape[0]
    assert np.isfinite(snap.poses).all()
    np.testing.assert_allclose(np.linalg.norm(snap.poses[:, 3:], axis=1), 1.0, atol=1e-6)
    for i, (entity, part) in enumerate(layout.parts):
        pos, quat = cleanup.backend.get_pose(entity, part)
        np.testing.assert_allclose(snap.poses[i], np.concatenate([pos, quat]), atol=1e-9)
    assert snap.step == 10
    assert "world `cleanup`" in snap.status and " step 10 " in snap.status
    assert snap.texts["score"] == "score: 0"
    assert snap.agents == list(cleanup.entities) and snap.entities == list(cleanup.entities.names)


def test_log_publication_is_shown(sim: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """A publication declared with display="log" shows each value as a line of the events, newest first, through
    its template; a value the template does not fit falls back to "topic: field=value"."""
    lock = lockstep(sim)
    assert lock.show().texts["events"] == "no events yet"
    publisher = sim.publications.declare(Publication("/test/log", "std_msgs/msg/String", "events", display="log",
                                                     display_format="got {data}"))
    publisher.publish({"data": "first"})
    assert lock.tick()
    publisher.publish({"data": "second"})
    publisher.publish({"other": 7})
    snap = lock.show()
    assert snap.texts["events"].split("  \n") == ["/test/log: other=7", "got second", "got first"]
    assert "world `coretest`" in snap.status


def test_failing_command_is_a_note(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """A command that raises becomes a note naming the error; the simulation keeps stepping."""
    lock = lockstep(cleanup)
    assert lock.tick()
    def broken(sim: Simulation) -> str | None:
        raise ZeroDivisionError("division by zero")
    snap = lock.run(broken)
    assert newest_note(snap) == "that did not work: ZeroDivisionError: division by zero"
    before = cleanup.worlds.elapsed_steps
    assert [lock.tick() for _ in range(3)] == [True] * 3
    assert cleanup.worlds.elapsed_steps == before + 3


# ------------------------------------------------------------------ the server
def test_taken_port_is_refused(viewers: Callable[..., WebViewer]) -> None:
    """An explicit port another program listens on is refused with ViewerError naming the port."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        viewer = viewers(port)
        with pytest.raises(ViewerError, match=f"port {port} on 127.0.0.1 is in use by another program"):
            viewer.open()
    with pytest.raises(ViewerError, match="not open yet"):
        viewer.url  # noqa: B018 - the property raises


def test_default_port_taken_takes_the_next(viewers: Callable[..., WebViewer]) -> None:
    """With no port given and 8080 taken, the viewer listens on a later port, and its URL says which."""
    blocker = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        try:
            blocker.bind(("127.0.0.1", DEFAULT_PORT))
            blocker.listen()
        except OSError:
            pass  # another program holds 8080 already: the case under test all the same
        viewer = viewers(None)
        viewer.open()
        port = port_of(viewer)
        assert port > DEFAULT_PORT
        assert viewer.url == f"http://127.0.0.1:{port}"
        with socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT):
            pass  # the viewer listens there
    finally:
        blocker.close()


@pytest.mark.parametrize(("kwargs", "valid"), [
    ({"rate": 0}, r"valid: 0 < rate <= 120"),
    ({"rate": 1000}, r"valid: 0 < rate <= 120"),
    ({"rate": float("nan")}, r"valid: 0 < rate <= 120"),
    ({"port": 70000}, r"valid: 1\.\.65535"),
    ({"port": 0}, r"valid: 1\.\.65535"),
])
def test_out_of_range_arguments_are_refused(kwargs: dict[str, float], valid: str) -> None:
    """A rate outside (0, 120] Hz or a port outside 1..65535 is refused with the valid range."""
    with pytest.raises(ViewerError, match=valid):
        WebViewer(**kwargs)  # type: ignore[arg-type]


def test_run_services_the_viewer_and_frees_its_port(cleanup: Simulation,
                                                    viewers: Callable[..., WebViewer]) -> None:
    """sigcore.sim.run with the viewer as its transport runs all 200 steps, services the viewer between steps
    (a command queued at step 100 runs before step 101) and stops its server: the port is free again."""
    port = free_port()
    viewer = viewers(port)
    ran: list[int] = []

    def at_step_100(sim: Simulation) -> None:
        if sim.worlds.elapsed_steps == 100:
            viewer._post(lambda s: ran.append(s.worlds.elapsed_steps))

    taken: list[Snapshot] = []
    viewer.snapshot_observers.append(taken.append)
    cleanup.events.subscribe("step", at_step_100)
    report = run(cleanup, steps=200, transport=[viewer], realtime_factor=None)
    assert (report.error, report.stopped_by, report.steps) == (None, None, 200)
    assert ran == [100]
    assert taken and taken[0].layout is not None and taken[0].step == 0
    with pytest.raises(ViewerError, match="not open yet"):
        viewer.url  # noqa: B018 - the property raises
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", port))  # raises OSError if the server still held it


# ------------------------------------------------------------------ the viewer's process
def test_requests_from_the_panel(cleanup: Simulation, lockstep: Callable[[Simulation], Lockstep]) -> None:
    """The panel's requests (plain tuples from the viewer's process) become the commands: ("step", 3) queues three
    steps, ("overlay", "scan", True) turns the scan on; an unknown request, one with the wrong arguments and an
    unknown overlay are notes naming what was sent, and change nothing."""
    lock = lockstep(cleanup)
    lock.run(lock.viewer._request(("pause",)))
    lock.run(lock.viewer._request(("step", 3)))
    assert (cleanup.control.paused, cleanup.control.pending_steps) == (True, 3)
    assert lock.run(lock.viewer._request(("overlay", "scan", True))).scan is not None
    snap = lock.run(lock.viewer._request(("launch", "rocket")))
    assert newest_note(snap) == "the viewer sent a request sigcore does not know: ('launch', 'rocket')"
    snap = lock.run(lock.viewer._request(("step",)))
    assert newest_note(snap) == "the viewer sent a request sigcore does not know: ('step',)"
    snap = lock.run(lock.viewer._request(("overlay", "smoke", True)))
    assert newest_note(snap).startswith("unknown overlay 'smoke'; valid: names, frames, scan")
    assert cleanup.control.pending_steps == 3


@pytest.mark.slow
def test_a_crashed_viewer_process_leaves_the_run_going(cleanup: Simulation, viewers: Callable[..., WebViewer],
                                                        caplog: pytest.LogCaptureFixture) -> None:
    """The viewer's process killed in the middle of a run (SIGKILL: it cannot say goodbye): the run goes on to its
    last step without an error, a warning says the viewer is gone, and stop() afterwards is clean."""
    import os
    import signal

    viewer = viewers(free_port())
    viewer.open()
    pid = viewer.process_id
    assert pid is not None

    def kill_at_step_50(sim: Simulation) -> None:
        if sim.worlds.elapsed_steps == 50:
            os.kill(pid, signal.SIGKILL)
            assert viewer._proc is not None
            viewer._proc.wait(timeout=TIMEOUT)  # gone, its end of the socket closed, before step 51

    cleanup.events.subscribe("step", kill_at_step_50)
    with caplog.at_level("WARNING", logger="sigcore.viewer"):
        report = run(cleanup, steps=3000, transport=[viewer], realtime_factor=None)
    assert (report.error, report.stopped_by, report.steps) == (None, None, 3000)
    assert any("its process ended" in r.getMessage() and "goes on without the viewer" in r.getMessage()
               for r in caplog.records)
    assert viewer.process_id is None
