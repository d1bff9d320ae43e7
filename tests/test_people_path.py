"""People walking paths (issue 30, part 3): a ``<path>`` of waypoints in the world file or given at run time, walked
on time on feet that do not slide, waits and conditions (time, a robot near, a message), loops; paths that cannot be
walked refused with where and why; one motion source at a time; spawned walkers; reset; a recorded path replayed
bit for bit. Both backends where the backend matters (the walls are found by its rays, it moves the box)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from replaying import resimulate

from sigcore.agent.exceptions import ApiError
from sigcore.record import Recorder
from sigcore.record.replay import load_recording
from sigcore.sim import Simulation
from sigcore.sim.paths import TURN_RATE
from sigcore.world import WalkPath, Waypoint, WorldError, parse_world
from sigcore.world.resources import SpawnRequest

BACKENDS = ("mujoco", "bullet")
ROOT = Path(__file__).parent.parent
BOT = ROOT / "tests" / "data" / "sim" / "minibot.urdf"
ROBOT = (f'<robot name="bot" urdf="{BOT}" pose="{{}}"><drive left="wheel_l_joint" right="wheel_r_joint" '
         'radius="0.1" separation="0.36"/></robot>')
DT = 0.002


def _file(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "w.xml"
    path.write_text(f'<world name="w" timestep="{DT}">\n{body}\n</world>\n')
    return path


def _sim(tmp_path: Path, body: str, backend: str = "mujoco") -> Simulation:
    return Simulation(parse_world(_file(tmp_path, body)), backend)


def _xy(sim: Simulation, name: str) -> np.ndarray:
    return sim.backend.get_pose(name)[0][:2].copy()


def _path(points: str, speed: float = 1.0, extra: str = "") -> str:
    """A ``<path>`` element of ``points`` 'x,y x,y ...'."""
    rows = "".join(f'<waypoint x="{p.split(",")[0]}" y="{p.split(",")[1]}"/>' for p in points.split())
    return f'<path speed="{speed}" {extra}>{rows}</path>'


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_three_waypoint_path_is_walked_on_time_on_feet_that_do_not_slide(tmp_path: Path, backend: str) -> None:
    """At 1.0 m/s through (2, 0), (2, 1.5), (0.5, 1.5): each waypoint is reached within 5 cm and within 5 % of the
    expected time (the legs' lengths over the speed plus the turns over TURN_RATE); a foot on the floor moves less
    than 2 cm while it is down."""
    sim = _sim(tmp_path, f'<human name="h" pose="0 0 0">{_path("2,0 2,1.5 0.5,1.5")}</human>', backend)
    body = sim.entities.people.body("h")
    points = [(2.0, 0.0), (2.0, 1.5), (0.5, 1.5)]
    expected, t, heading, here = [], 0.0, 0.0, (0.0, 0.0)
    for p in points:
        bearing = math.atan2(p[1] - here[1], p[0] - here[0])
        t += abs(math.remainder(bearing - heading, math.tau)) / TURN_RATE + math.dist(here, p) / 1.0
        expected.append(t)
        heading, here = bearing, p
    arrivals: list[tuple[float, float]] = []  # (time, distance to the waypoint) when progress moved past it
    ankles: dict[str, list[np.ndarray]] = {"l": [], "r": []}
    last = 0
    while len(arrivals) < 3 and sim.time < 8.0:
        sim.step(1)
        progress = sim.entities.people.progress("h")
        assert progress is not None
        for side in "lr":
            ankles[side].append(sim.backend.get_pose("h", f"{side}_ankle")[0].copy())
        reached = progress.waypoint + (progress.state in ("waiting", "done"))
        if reached > last:
            arrivals.append((sim.time, float(np.linalg.norm(_xy(sim, "h") - points[last]))))
            last = reached
    assert len(arrivals) == 3, arrivals
    for (when, off), want in zip(arrivals, expected, strict=True):
        assert off < 0.05 and abs(when - want) <= 0.05 * want, (when, want, off)
    assert sim.entities.people.progress("h").state == "done"
    for side in "lr":
        track = np.array(ankles[side])
        down = track[:, 2] < body.ankle_height + 1e-3
        edges = np.flatnonzero(np.diff(np.r_[0, down.astype(int), 0]))
        slides = [float(np.linalg.norm(track[a:b, :2] - track[a, :2], axis=1).max()) for a, b in edges.reshape(-1, 2)]
        assert len(slides) >= 3 and max(slides) < 0.02, (side, slides)


def test_a_wait_holds_the_person_for_its_time(tmp_path: Path) -> None:
    """``wait="1.5"`` at the first waypoint: the person stands there 1.5 s (to the step), then walks on."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"><path><waypoint x="1" y="0" wait="1.5"/>'
                         '<waypoint x="2" y="0"/></path></human>')
    people = sim.entities.people
    while people.progress("h").state != "waiting":
        sim.step(1)
    arrived = sim.time
    assert people.progress("h").waiting_for.endswith(" s")
    while people.progress("h").state == "waiting":
        np.testing.assert_allclose(_xy(sim, "h"), [1.0, 0.0], atol=1e-6)
        sim.step(1)
    assert sim.time - arrived == pytest.approx(1.5, abs=1.5 * DT)
    sim.step(500)
    assert _xy(sim, "h")[0] > 1.5


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_person_stopped_by_a_condition_walks_on_when_the_robot_comes_near(tmp_path: Path, backend: str) -> None:
    """SIGVerse's follow-me operator: it waits at its first waypoint until the robot is within 2 m. A robot 4 m away
    keeps it waiting; driven closer, the person sets off at the step it comes within 2 m (to one step's travel)."""
    sim = _sim(tmp_path, '<human name="op" pose="0 0 0"><path><waypoint x="0" y="0" until_near="bot" within="2"/>'
                         '<waypoint x="3" y="0"/></path></human>' + ROBOT.format("-4 0 0.1"), backend)
    people = sim.entities.people
    sim.step(1000)
    assert people.progress("op").state == "waiting" and people.progress("op").waiting_for == "bot within 2 m"
    np.testing.assert_allclose(_xy(sim, "op"), [0, 0], atol=1e-9)
    gap = math.inf
    for _ in range(80):
        sim.robot("bot").set_base_velocity(0.5, 0.0)
        sim.step(50)
        if people.progress("op").waypoint == 1:
            break
        gap = float(np.linalg.norm(_xy(sim, "bot") - _xy(sim, "op")))
        assert gap > 2.0
    assert people.progress("op").waypoint == 1, gap
    assert gap - 2.0 < 0.5 * 50 * DT + 0.01  # it set off within the 50 steps in which the robot came within 2 m
    sim.robot("bot").set_base_velocity(0.0, 0.0)
    sim.step(2000)
    assert people.progress("op").state == "done"
    assert np.linalg.norm(_xy(sim, "op") - [3, 0]) < 0.05


def test_a_person_waits_for_its_message(tmp_path: Path) -> None:
    """``until_message="go"``: another text or a message to someone else does not release it; "go" does, at once."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"><path><waypoint x="0.5" y="0" until_message="go"/>'
                         '<waypoint x="1.5" y="0"/></path></human><human name="other" pose="0 3 0"/>')
    people = sim.entities.people
    sim.step(1000)
    assert people.progress("h").waiting_for == "message 'go'"
    sim.inputs.message("viewer", "h", "stop")
    sim.inputs.message("viewer", "other", "go")
    sim.step(200)
    assert people.progress("h").state == "waiting"
    sim.inputs.message("viewer", "h", "go")
    sim.step(2)
    assert people.progress("h").waypoint == 1 and people.progress("h").state in ("turning", "walking")
    sim.step(1500)
    assert np.linalg.norm(_xy(sim, "h") - [1.5, 0]) < 0.05


def test_a_looping_path_goes_round_again(tmp_path: Path) -> None:
    """``loop="true"`` round a 1 m square: back at the start after each lap, the laps counted."""
    square = _path("1,0 1,1 0,1 0,0", extra='loop="true"')
    sim = _sim(tmp_path, f'<human name="h" pose="0 0 0">{square}</human>')
    people = sim.entities.people
    for lap in (1, 2):
        while people.progress("h").laps < lap:
            sim.step(1)
        np.testing.assert_allclose(_xy(sim, "h"), [0.0, 0.0], atol=0.01)
    assert people.progress("h").state != "done"


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_path_through_a_wall_is_refused_where_it_is_written(tmp_path: Path, backend: str) -> None:
    """A leg through a static wall is a WorldError at its waypoint's line, naming the wall and where; a leg past a
    light box loads, and the person pushes the box out of its way."""
    wall = '<object name="wall" shape="box" size="0.1 4 1" static="true" pose="1 0 0.5"/>'
    path = _file(tmp_path, f'{wall}\n<human name="h" pose="0 0 0">\n<path>\n<waypoint x="0" y="1"/>\n'
                           '<waypoint x="2" y="1"/>\n</path>\n</human>')
    with pytest.raises(WorldError) as info:
        Simulation(parse_world(path), backend)
    (issue,) = info.value.issues
    assert (issue.line, issue.element) == (6, "waypoint")
    assert "passes through the static 'wall' at (0.95, 1.00)" in issue.message and "add a waypoint" in issue.message
    sim = _sim(tmp_path, '<object name="box" shape="box" size="0.4 0.4 0.4" mass="0.5" pose="1 0 0.2"/>'
                         f'<human name="h" pose="0 0 0">{_path("2.5,0", speed=0.8)}</human>', backend)
    sim.step(2500)
    assert np.linalg.norm(_xy(sim, "h") - [2.5, 0]) < 0.05
    assert np.linalg.norm(_xy(sim, "box") - [1.0, 0.0]) > 0.5


def test_impossible_conditions_and_names_are_refused(tmp_path: Path) -> None:
    """An ``until_near`` on a static object too far from the waypoint, on nothing, on the person itself: each a
    located issue naming what is wrong and what is valid; a malformed path is the parser's."""
    table = '<object name="table" shape="box" size="1 1 0.7" static="true" pose="5 5 0.35"/>'
    path = _file(tmp_path, f'{table}\n<human name="h" pose="0 0 0"><path>\n<waypoint x="1" y="0" until_near="table"/>'
                           '\n<waypoint x="2" y="0" until_near="nobody"/>\n<waypoint x="3" y="0" until_near="h"/>'
                           '\n</path></human>')
    with pytest.raises(WorldError) as info:
        Simulation(parse_world(path), "mujoco")
    issues = info.value.issues
    assert [(i.line, i.attribute) for i in issues] == [(4, "until_near"), (5, "until_near"), (6, "until_near")]
    assert "'table' within 2 m can never hold: 'table' is static, 6.40 m from the waypoint" in issues[0].message
    assert "no entity 'nobody'; valid: another entity: table" in issues[1].message
    assert "the person itself" in issues[2].message
    for body, says in (('<path speed="1"/>', "a <path> with no points"),
                       ('<path speed="3"><waypoint x="1" y="0"/></path>', "valid: 0.2 <= speed <= 1.8"),
                       ('<path><waypoint x="1" y="0" within="1"/></path>', "'within' is the distance of 'until_near'"),
                       ('<path><waypoint x="1" y="nan"/></path>', "not a finite number"),
                       ('<path><waypoint x="1" y="0"/></path><path><waypoint x="1" y="0"/></path>',
                        "<path> may appear only once")):
        with pytest.raises(WorldError) as info:
            parse_world(_file(tmp_path, f'<human name="h">{body}</human>'))
        assert says in str(info.value), body


def test_one_source_at_a_time_and_bad_paths_at_run_time(tmp_path: Path) -> None:
    """A path given at run time ends a walk by velocity; a walk by velocity ends the path; a path through a wall is
    refused with the wall's name and what went on before goes on."""
    sim = _sim(tmp_path, '<object name="wall" shape="box" size="0.1 4 1" static="true" pose="3 0 0.5"/>'
                         '<human name="h" pose="0 0 0"/>')
    people = sim.entities.people
    sim.inputs.person_velocity("h", 1.0, 0.0)
    sim.step(500)
    sim.inputs.person_path("h", WalkPath(waypoints=(Waypoint(x=1.0, y=1.0),)))
    assert people.velocity("h") == (0.0, 0.0) and people.progress("h").state == "turning"
    sim.step(2500)
    assert np.linalg.norm(_xy(sim, "h") - [1.0, 1.0]) < 0.05
    sim.inputs.person_path("h", WalkPath(waypoints=(Waypoint(x=1.0, y=-1.0),)))
    sim.step(100)
    sim.inputs.person_velocity("h", 0.5, 0.0)
    assert people.progress("h") is None
    with pytest.raises(ApiError, match=r"waypoint 0: the leg from the start .* passes through the static 'wall'"):
        people.follow("h", WalkPath(waypoints=(Waypoint(x=5.0, y=0.0),)))
    with pytest.raises(ApiError, match="no person 'nobody'; people"):
        people.follow("nobody", WalkPath(waypoints=(Waypoint(x=5.0, y=0.0),)))
    assert people.velocity("h") == (0.5, 0.0)
    sim.step(100)
    assert people.walking("h")


def test_spawned_walkers_and_a_reset(tmp_path: Path) -> None:
    """A person spawned with a ``<path>`` walks it; one whose path goes through a wall is refused; a reset puts the
    world file's walker back at its start, walking its path again."""
    sim = _sim(tmp_path, '<object name="wall" shape="box" size="0.1 4 1" static="true" pose="3 0 0.5"/>'
                         f'<human name="h" pose="0 0 0">{_path("1,0")}</human>')
    good = f'<human name="s">{_path("0,-2")}</human>'
    bad = f'<human name="t">{_path("5,1")}</human>'
    (refused,) = sim.inputs.spawn([SpawnRequest(resource=bad, xyz=(0.0, 1.0, 0.0))])
    assert "'t' cannot walk its <path>" in str(refused) and "'wall' at (2.95, 1.00)" in str(refused)
    assert sim.inputs.spawn([SpawnRequest(resource=good, xyz=(0.0, 1.0, 0.0))]) == ["s"]
    sim.step(3000)
    assert np.linalg.norm(_xy(sim, "s") - [0, -2]) < 0.05 and np.linalg.norm(_xy(sim, "h") - [1, 0]) < 0.05
    sim.reset()
    np.testing.assert_allclose(_xy(sim, "h"), [0, 0], atol=1e-9)
    assert sim.entities.people.progress("h").waypoint == 0
    sim.step(1500)
    assert np.linalg.norm(_xy(sim, "h") - [1, 0]) < 0.05


def test_a_recorded_path_replays_bit_for_bit(tmp_path: Path) -> None:
    """A path given at run time and the message it waits for are in the input log; replayed, every frame ends bit for
    bit where it was; without the message the person is still waiting."""
    world = _file(tmp_path, '<human name="h" pose="0 0 0"/>'
                            '<object name="box" shape="box" size="0.3 0.3 0.3" mass="0.5" pose="1.0 0.1 0.15"/>')
    sim = Simulation(parse_world(world), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    path = WalkPath(speed=0.9, waypoints=(Waypoint(x=0.5, y=0.0, until_message="go"), Waypoint(x=2.0, y=0.5)))
    for step in range(2500):
        if step == 10:
            sim.inputs.person_path("h", path)
        if step == 900:
            sim.inputs.message("viewer", "h", "go")
        sim.step()
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind) for i in rec.inputs] == [(10, "person_path"), (900, "message")]

    equal, worst, _ = resimulate(rec, tmp_path / "world", rec.inputs)
    assert equal and worst == 0.0
    equal, worst, _ = resimulate(rec, tmp_path / "world", [i for i in rec.inputs if i.kind != "message"])
    assert not equal and worst > 1.0


def test_a_person_waiting_for_a_deleted_entity_walks_on(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """``until_near`` an entity that is deleted while the person waits: it walks on at once, with one warning that
    names both."""
    sim = _sim(tmp_path, '<human name="op" pose="0 0 0"><path><waypoint x="0" y="0" until_near="bot"/>'
                         '<waypoint x="1" y="0"/></path></human>' + ROBOT.format("-4 0 0.1"))
    sim.step(200)
    assert sim.entities.people.progress("op").state == "waiting"
    sim.inputs.delete(["bot"])
    with caplog.at_level("WARNING", logger="sigcore.people"):
        sim.step(1000)
    assert sim.entities.people.progress("op").state == "done"
    assert np.linalg.norm(_xy(sim, "op") - [1, 0]) < 0.05
    said = [r.getMessage() for r in caplog.records if r.name == "sigcore.people"]
    assert said == ["'op' waits for 'bot' to come near, which is gone: it walks on"]
