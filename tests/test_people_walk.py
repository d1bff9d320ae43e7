"""People walking by velocity (issue 30, part 2: the procedural gait), on both backends, in lockstep: the distance,
feet that do not slide, a lidar's view of the stride, turning on the spot, stopping, refusals, pushing, contacts,
and a recorded walk replayed bit for bit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from replaying import resimulate

from sigcore.agent import CollisionEvent
from sigcore.agent.exceptions import ApiError
from sigcore.geometry import quat_yaw
from sigcore.record import Recorder
from sigcore.record.replay import load_recording
from sigcore.sim import Simulation
from sigcore.sim.gait import SETTLE
from sigcore.world import parse_world

BACKENDS = ("mujoco", "bullet")
ROOT = Path(__file__).parent.parent
BOT = ROOT / "tests" / "data" / "sim" / "minibot.urdf"


def _sim(tmp_path: Path, body: str, backend: str) -> Simulation:
    path = tmp_path / "w.xml"
    path.write_text(f'<world name="w" timestep="0.002">\n{body}\n</world>\n')
    return Simulation(parse_world(path), backend)


def _track(sim: Simulation, person: str, steps: int) -> dict[str, np.ndarray]:
    """Each ankle's world position after each of ``steps`` steps, and the feet frame's (keys l, r, root)."""
    out: dict[str, list[np.ndarray]] = {"l": [], "r": [], "root": []}
    for _ in range(steps):
        sim.step(1)
        for side in "lr":
            out[side].append(sim.backend.get_pose(person, f"{side}_ankle")[0].copy())
        out["root"].append(sim.backend.get_pose(person)[0].copy())
    return {k: np.array(v) for k, v in out.items()}


def _stances(ankle: np.ndarray, height: float) -> list[np.ndarray]:
    """The runs of positions where the ankle is at its standing height (the foot on the floor), within 1 mm."""
    down = ankle[:, 2] < height + 1e-3
    runs, start = [], None
    for i, d in enumerate([*down, False]):
        if d and start is None:
            start = i
        elif not d and start is not None:
            runs.append(ankle[start:i])
            start = None
    return runs


@pytest.mark.parametrize("backend", BACKENDS)
def test_walking_goes_the_distance_on_feet_that_do_not_slide(tmp_path: Path, backend: str) -> None:
    """At 1.0 m/s for 3 s a person walks 3 m (within 5 cm), stepping with each foot in turn; a foot on the floor
    moves less than 2 cm while it is down; the pelvis bobs by at most 6 cm."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/>', backend)
    body = sim.entities.people.body("h")
    sim.inputs.person_velocity("h", 1.0, 0.0)
    track = _track(sim, "h", 1500)
    assert track["root"][-1][0] == pytest.approx(3.0, abs=0.05) and abs(track["root"][-1][1]) < 1e-9
    for side in "lr":
        stances = _stances(track[side], body.ankle_height)
        assert len(stances) >= 3, side
        slides = [float(np.linalg.norm(s[:, :2] - s[0, :2], axis=1).max()) for s in stances]
        assert max(slides) < 0.02, (side, slides)
        assert track[side][:, 2].max() > body.ankle_height + 0.03  # it was lifted
    assert -0.06 <= track["root"][:, 2].min() <= track["root"][:, 2].max() <= 1e-9


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_lidar_sees_the_legs_move_apart_and_together(tmp_path: Path, backend: str) -> None:
    """Rays at 0.25 m across the path of a person walking past 2 m away: the distance between its two legs
    changes with the gait by more than 0.2 m."""
    sim = _sim(tmp_path, '<human name="h" pose="2 -1 0 0 0 1.5708"/>', backend)
    sim.inputs.person_velocity("h", 1.0, 0.0)
    yaws = np.linspace(-0.8, 0.8, 1601)
    dirs = np.stack([np.cos(yaws), np.sin(yaws), np.zeros_like(yaws)], axis=1)
    gaps = []
    for _ in range(40):
        sim.step(25)
        dist = sim.backend.ray_cast(np.array([0.0, 0.0, 0.25]), dirs, 6.0)
        hit = np.flatnonzero(np.isfinite(dist))
        points = dirs[hit] * dist[hit][:, None]
        if len(hit) > 1:
            gaps.append(float(np.linalg.norm(points[-1] - points[0])))
    assert len(gaps) > 30
    assert max(gaps) - min(gaps) > 0.2, gaps


@pytest.mark.parametrize("backend", BACKENDS)
def test_turning_on_the_spot_steps_round_where_it_stands(tmp_path: Path, backend: str) -> None:
    """Told to turn at 1 rad/s without walking, a person turns by π in π s on the spot (its feet frame stays within
    2 cm) and steps with both feet."""
    sim = _sim(tmp_path, '<human name="h" pose="1 1 0"/>', backend)
    body = sim.entities.people.body("h")
    sim.inputs.person_velocity("h", 0.0, 1.0)
    track = _track(sim, "h", round(math.pi / 0.002))
    yaw = quat_yaw(sim.backend.get_pose("h")[1])
    assert abs(math.atan2(math.sin(yaw - math.pi), math.cos(yaw - math.pi))) < 0.01
    assert np.abs(track["root"][:, :2] - [1, 1]).max() < 0.02
    assert all(track[side][:, 2].max() > body.ankle_height + 0.02 for side in "lr")


def test_stopping_ends_the_step_and_stands_on_both_feet(tmp_path: Path) -> None:
    """After (0, 0) the step under way ends within SETTLE s: both feet down, the person no longer walking, where
    it stopped; it stays there."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/>', "mujoco")
    body = sim.entities.people.body("h")
    sim.inputs.person_velocity("h", 1.2, 0.3)
    sim.step(310)
    sim.inputs.person_velocity("h", 0.0, 0.0)
    sim.step(round(SETTLE / 0.002) + 2)
    assert not sim.entities.people.walking("h")
    for side in "lr":
        assert sim.backend.get_pose("h", f"{side}_ankle")[0][2] == pytest.approx(body.ankle_height, abs=1e-6)
    here = sim.backend.get_pose("h")[0].copy()
    sim.step(200)
    np.testing.assert_array_equal(sim.backend.get_pose("h")[0], here)


def test_bad_walking_commands_are_refused_and_the_walk_goes_on(tmp_path: Path) -> None:
    """Too fast, too fast backward, too fast a turn, NaN, no such person, a robot: each refused naming what is
    valid; the last good command stays in force."""
    sim = _sim(tmp_path, f'<human name="h"/><robot name="bot" urdf="{BOT}"/>', "mujoco")
    sim.inputs.person_velocity("h", 0.8, 0.0)
    for args, match in ((("h", 2.5, 0.0), "-0.6 to 1.8 m/s"), (("h", -1.0, 0.0), "-0.6 to 1.8 m/s"),
                        (("h", 0.5, 3.0), "at most 2 rad/s"), (("h", float("nan"), 0.0), "finite"),
                        (("nobody", 1.0, 0.0), "people \\(<human>\\): h"), (("bot", 1.0, 0.0), "no person 'bot'")):
        with pytest.raises(ApiError, match=match):
            sim.inputs.person_velocity(*args)
    assert sim.entities.people.velocity("h") == (0.8, 0.0)
    sim.step(500)
    assert sim.backend.get_pose("h")[0][0] == pytest.approx(0.8, abs=0.01)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_walking_person_knocks_a_box_out_of_the_way(tmp_path: Path, backend: str) -> None:
    """A person walking at 0.8 m/s into a 0.5 kg box knocks it out of the way (it moves by more than 0.5 m), and is
    not slowed by it."""
    sim = _sim(tmp_path, '<human name="h" pose="0 0 0"/>'
                         '<object name="box" shape="box" size="0.4 0.4 0.4" mass="0.5" pose="0.8 0 0.2"/>', backend)
    sim.inputs.person_velocity("h", 0.8, 0.0)
    sim.step(1500)
    assert sim.backend.get_pose("h")[0][0] == pytest.approx(2.4, abs=0.01)
    assert np.linalg.norm(sim.backend.get_pose("box")[0][:2] - [0.8, 0.0]) > 0.5


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_robot_driving_into_a_person_gets_one_collision_naming_it(tmp_path: Path, backend: str) -> None:
    """A robot driven into a standing person gets one collision event naming the person per part that touches it
    (one contact episode while it pushes), and the person does not move."""
    sim = _sim(tmp_path, f'<human name="h" pose="1.2 0 0 0 0 3.14159"/><robot name="bot" urdf="{BOT}">'
                         '<drive left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.36"/>'
                         '</robot>', backend)
    events: list[CollisionEvent] = []
    sim.events.subscribe("collision", events.append)
    for _ in range(4):
        sim.robot("bot").set_base_velocity(0.4, 0.0)
        sim.step(500)
    mine = [e for e in events if e.agent == "bot" and e.other == "h"]
    assert mine and len(mine) == len({e.part for e in mine}), mine
    assert any(e.agent == "h" and e.other == "bot" for e in events)
    np.testing.assert_allclose(sim.backend.get_pose("h")[0], [1.2, 0, 0], atol=1e-9)


def test_a_recorded_walk_replays_bit_for_bit(tmp_path: Path) -> None:
    """A walk started, turned and stopped through ``sim.inputs`` is in the input log at its steps; replayed, every
    frame (the person's links too) ends bit for bit where it was; without the turn it does not."""
    world = tmp_path / "w.xml"
    world.write_text('<world name="w" timestep="0.002"><human name="h" pose="0 0 0"/>'
                     '<object name="box" shape="box" size="0.3 0.3 0.3" mass="0.5" pose="1.0 0.14 0.15"/></world>')
    sim = Simulation(parse_world(world), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    plan = {10: (1.0, 0.0), 600: (0.6, -0.8), 1100: (0.0, 0.0)}
    for step in range(1400):
        if step in plan:
            sim.inputs.person_velocity("h", *plan[step])
        sim.step()
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert [(i.step, i.kind, i.args["linear"]) for i in rec.inputs] == [
        (10, "person_velocity", 1.0), (600, "person_velocity", 0.6), (1100, "person_velocity", 0.0)]

    equal, worst, _ = resimulate(rec, tmp_path / "world", rec.inputs)
    assert equal and worst == 0.0
    equal, worst, _ = resimulate(rec, tmp_path / "world", [i for i in rec.inputs if i.step != 600])
    assert not equal and worst > 0.1
