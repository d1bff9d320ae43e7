"""Randomised worlds: ``<randomize>`` drawn with a seed (``sigcore.world.randomize``, ``sigcore run --seed N``).

The same seed gives the same world, in this process and in fresh ones; different seeds give different layouts, each
valid, inside its region or on its table top, without overlaps; a region too small and every bad input are reported
with their ``file:line:column``; a seeded run is recorded with its seed and replays bit for bit. No ROS.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from sigcore import plugins
from sigcore.cli import app
from sigcore.sim import Simulation, run
from sigcore.world import BareAgent, Entity, Object, World, WorldError, parse_world
from sigcore.world.exceptions import RandomizeError, SeedError
from sigcore.world.footprints import local_bounds
from sigcore.world.randomization import Choice, Option, Randomize, RandomPose
from sigcore.world.randomize import apply_seed, draw, sample

ROOT = Path(__file__).resolve().parent.parent
CLEANUP = ROOT / "worlds" / "cleanup.xml"
RANDOM = ROOT / "worlds" / "cleanup_random.xml"
TABLE = ROOT / "worlds" / "models" / "table" / "table.urdf"
MUG = ROOT / "tests" / "data" / "worlds" / "models" / "mug.obj"
DOCS = ROOT / "docs" / "world-format.md"
ITEMS = {"can_0": 0.06, "petbottle_1": 0.1, "apple_2": 0.04}
"""The trash of the clean-up world and the height of its centre above its bottom [m]."""
RADIUS = {"can_0": 0.033, "petbottle_1": 0.033, "apple_2": 0.04}
TOPS = {"table_0": (-2.1, 1.6, -0.9, 2.2), "table_1": (0.9, 1.6, 2.1, 2.2)}
"""The tables' tops in world, from worlds/cleanup.xml's comment: x0 y0 x1 y1 [m], at z 0.70."""


def sigcore(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sigcore", *args], capture_output=True, text=True, cwd=ROOT,
                          timeout=120, env={**os.environ, **(env or {})})


@pytest.fixture(scope="module")
def world() -> World:
    """worlds/cleanup_random.xml, parsed once."""
    return parse_world(RANDOM)


def _write(tmp_path: Path, body: str, name: str = "world.xml") -> Path:
    path = tmp_path / name
    path.write_text(body, encoding="utf-8")
    return path


# ------------------------------------------------------------------------------------------ the same seed


def test_the_same_seed_gives_the_same_world(world: World) -> None:
    """Two draws with one seed, from two parses, are equal to the last field; the parsed world is left as written;
    another seed gives another world; the drawn world knows its seed."""
    first, second = sample(world, 5), sample(parse_world(RANDOM), 5)
    assert first.model_dump() == second.model_dump()
    assert first.sample_seed == second.sample_seed == 5 and world.sample_seed is None
    assert world.model_dump() == parse_world(RANDOM).model_dump()
    assert world.agent("can_0").pose.xyz == (-1.8, 1.75, 0.761)  # untouched: the file's pose
    assert sample(world, 6).model_dump() != first.model_dump()
    assert first.seed == 0 and apply_seed(world, 5).seed == 5  # the noise seed: the file's, or --seed's
    assert apply_seed(world, 5).model_dump() == first.model_copy(update={"seed": 5}).model_dump()


@pytest.mark.slow
def test_the_same_seed_gives_the_same_layout_in_fresh_processes(world: World) -> None:
    """`sigcore check --seed 7` prints the same layout in two processes (different hash seeds, so no set order
    leaks in), the one this process draws; another seed prints another."""
    runs = [sigcore("check", str(RANDOM), "--seed", "7", "--transport", "none", env={"PYTHONHASHSEED": h})
            for h in ("1", "2")]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr
    assert runs[0].stdout == runs[1].stdout
    layout = draw(world, 7)
    for p in layout.placements:
        line = next(line for line in runs[0].stdout.splitlines() if line.split()[:1] == [p.entity])
        assert f"x {p.xyz[0]:10.6f}  y {p.xyz[1]:10.6f}  z {p.xyz[2]:9.6f}  yaw {p.rpy[2]:9.6f}" in line, line
    assert "seed 7 draws" in runs[0].stdout and ": ok (16 agents" in runs[0].stdout
    other = sigcore("check", str(RANDOM), "--seed", "8", "--transport", "none")
    assert other.returncode == 0 and other.stdout != runs[0].stdout


# ------------------------------------------------------------------------------------------ different seeds


def _entity(world: World, name: str) -> Entity:
    entity = world.agent(name)
    assert not isinstance(entity, BareAgent)
    return entity


def _footprint(world: World, name: str) -> tuple[float, float, float, float]:
    """The x-y box in world around an entity's visuals, computed here with numpy from its bounds and pose (roll and
    pitch are 0 in these worlds)."""
    entity = _entity(world, name)
    bounds = local_bounds(entity, world)
    assert bounds is not None
    lo, hi = np.array(bounds[0]), np.array(bounds[1])
    corners = np.array([[x, y] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])])
    yaw = entity.pose.rpy[2]
    turn = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    points = corners @ turn.T + np.array(entity.pose.xyz[:2])
    return points[:, 0].min(), points[:, 1].min(), points[:, 0].max(), points[:, 1].max()


def _apart(a: tuple[float, ...], b: tuple[float, ...], gap: float) -> bool:
    """Whether two x-y boxes are at least ``gap`` apart along x or along y."""
    return a[0] >= b[2] + gap or b[0] >= a[2] + gap or a[1] >= b[3] + gap or b[1] >= a[3] + gap


def test_twenty_seeds_give_different_valid_layouts(world: World) -> None:
    """20 seeds give at least 15 distinct layouts; each world builds on MuJoCo; every item is on a table top
    (footprint 2 cm inside its edges, y in the strip, z = top + half height + 1 mm, yaw in range), the robot's
    start is in its region; no two drawn footprints are closer than the clearance, and the robot overlaps no
    furniture or wall."""
    layouts = set()
    fixed = [e.name for e in world.entities if e.name not in (*ITEMS, "robot_000")]
    for seed in range(20):
        drawn = sample(world, seed)
        Simulation(drawn, "mujoco")  # a valid world: the backend builds it
        for agent in drawn.agents:
            assert type(agent).model_validate(agent.model_dump(exclude_unset=True)) == agent
        poses = {name: _entity(drawn, name).pose for name in (*ITEMS, "robot_000")}
        layouts.add(tuple((p.xyz, p.rpy) for p in poses.values()))
        for name, half in ITEMS.items():
            (x, y, z), (roll, pitch, yaw) = poses[name].xyz, poses[name].rpy
            r = RADIUS[name] + 0.02 - 1e-6
            on = [t for t, (x0, y0, x1, y1) in TOPS.items() if x0 + r <= x <= x1 - r and y0 + r <= y <= y1 - r]
            assert len(on) == 1, (seed, name, x, y)
            assert 1.70 - 1e-9 <= y <= 1.80 + 1e-9 and abs(z - (0.70 + half + 0.001)) < 1e-9, (seed, name, y, z)
            assert roll == pitch == 0.0 and -3.141593 <= yaw <= 3.141593
        (x, y, z), (roll, pitch, yaw) = poses["robot_000"].xyz, poses["robot_000"].rpy
        assert -4.5 <= x <= -3.5 and -1.0 <= y <= 1.0 and z == 0.0 and -0.3 <= yaw <= 0.3 and roll == pitch == 0
        boxes = {name: _footprint(drawn, name) for name in poses}
        for a, b in combinations(boxes, 2):
            assert _apart(boxes[a], boxes[b], 0.02 - 1e-6), (seed, a, b)
        for other in fixed:
            assert _apart(boxes["robot_000"], _footprint(drawn, other), 0.02 - 1e-6), (seed, other)
    assert len(layouts) >= 15


def test_a_turned_table_keeps_its_top(tmp_path: Path) -> None:
    """On a table turned by 90°, the drawn cans stay on its (turned) top: 0.6 m along x, 1.2 m along y."""
    path = _write(tmp_path, f'''<world>
  <object name="table" urdf="{TABLE}" static="true" pose="1 2 0 0 0 1.5707963"/>
  <object name="a" shape="cylinder" size="0.05 0.1" pose="0 0 0.5"/>
  <object name="b" shape="cylinder" size="0.05 0.1" pose="0 0 0.5"/>
  <randomize><pose entity="a" on="table"/><pose entity="b" on="table" yaw="-3 3"/></randomize>
</world>
''')
    world = parse_world(path)
    xs, ys = [], []
    for seed in range(30):
        drawn = sample(world, seed)
        for name in "ab":
            x, y, z = _entity(drawn, name).pose.xyz
            xs.append(x)
            ys.append(y)
            assert abs(x - 1) <= 0.3 - 0.07 + 1e-6 and abs(y - 2) <= 0.6 - 0.07 + 1e-6 and z == pytest.approx(0.751)
    assert max(ys) - min(ys) > 0.6 > max(xs) - min(xs)  # spread along the table's length, now world y


# ------------------------------------------------------------------------------------------ errors


@pytest.mark.slow
def test_a_region_too_small_gives_a_clear_error(tmp_path: Path) -> None:
    """Three 0.2 m boxes in a 0.1 m square: the second cannot be placed; the error is at its <pose>, names it, the
    region, the draws, what it overlapped, and what to change. A box larger than a table's top says that."""
    boxes = "".join(f'  <object name="b{i}" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>\n' for i in range(3))
    path = _write(tmp_path, f'''<world>
{boxes}  <randomize attempts="50">
    <pose entity="b0" region="0 0 0.1 0.1"/>
    <pose entity="b1" region="0 0 0.1 0.1"/>
    <pose entity="b2" region="0 0 0.1 0.1"/>
  </randomize>
</world>
''')
    world = parse_world(path)  # the input is valid: the problem shows only when drawing
    with pytest.raises(RandomizeError) as info:
        sample(world, 1)
    [issue] = info.value.issues
    assert (issue.file, issue.line, issue.column, issue.element) == (path, 7, 5, "pose")
    for words in ("no free place for 'b1' in region 0 0 0.1 0.1 in 50 draws", "50 overlapped b0",
                  "clearance of 0.02 m", "a larger region", "fewer entities", "a smaller 'clearance'", "attempts"):
        assert words in issue.message, issue.message
    r = sigcore("run", str(path), "--seed", "1", "--transport", "none", "--steps", "1")
    assert r.returncode == 2 and f"{path}:7:5: <pose>: no free place for 'b1'" in r.stderr and "Traceback" not in \
        r.stderr
    big = _write(tmp_path, f'''<world>
  <object name="table" urdf="{TABLE}" static="true"/>
  <object name="slab" shape="box" size="2 2 0.1" pose="0 0 1"/>
  <randomize attempts="10"><pose entity="slab" on="table"/></randomize>
</world>
''', "big.xml")
    with pytest.raises(RandomizeError, match="10 were too large for the top of table at their yaw"):
        sample(parse_world(big), 0)


BASE = f'''<world name="t">
  <object name="table_0" urdf="{TABLE}" static="true" pose="0 0 0"/>
  <object name="can_0" shape="cylinder" size="0.033 0.12" mass="0.05" pose="0 0 0.761"/>
  <object name="box_1" shape="box" size="0.1 0.1 0.1" pose="1 1 0.05"/>
  <object name="ghost" urdf="novis.urdf" static="true" pose="5 5 0"/>
  <object name="ramp" shape="box" size="1 1 0.1" static="true" pose="-3 3 0.3 0.3 0 0"/>
  <human name="man_0" pose="3 3 0"/>
  <agent name="moderator"/>
  <named_pose name="zone" pose="-2 -2 0" bounds="-0.5 -0.5 0 0.5 0.5 1"/>
  <named_pose name="spot" pose="-3 -3 0"/>
  <randomize>
    LINE
  </randomize>
</world>
'''
"""A world whose line 12 is the case's; ``ghost`` has no visuals (no bounds), ``ramp`` is tilted."""

BAD = [
    # (case, line 12, (column, element, attribute), fragments of the message)
    ("unknown entity", '<pose entity="can_9" region="0 0 1 1"/>', (11, "pose", "entity"),
     ("no entity 'can_9'", "valid: a robot, object or human: table_0, can_0, box_1, ghost, ramp, man_0")),
    ("bodiless agent", '<pose entity="moderator" region="0 0 1 1"/>', (11, "pose", "entity"),
     ("'moderator' is an <agent>, which has no body",)),
    ("empty region", '<pose entity="can_0" region=""/>', (26, "pose", "region"),
     ("expected 4 numbers, got 0", "valid: 'x0 y0 x1 y1' [m] with x0 <= x1 and y0 <= y1")),
    ("x0 > x1", '<pose entity="can_0" region="1 0 0 1"/>', (26, "pose", "region"),
     ("1 0 0 1 is an empty region (x0 > x1 or y0 > y1)", "valid: 'x0 y0 x1 y1'")),
    ("NaN", '<pose entity="can_0" region="0 nan 1 1"/>', (26, "pose", "region"),
     ("numbers must be finite, got '0 nan 1 1'",)),
    ("on a non-entity", '<pose entity="can_0" on="tabel_0"/>', (26, "pose", "on"),
     ("no entity 'tabel_0'", "valid: robots, objects or humans left in place: table_0, box_1")),
    ("on an entity without bounds", '<pose entity="can_0" on="ghost"/>', (26, "pose", "on"),
     ("'ghost' has no bounds", "valid: an entity with visuals")),
    ("on a tilted entity", '<pose entity="can_0" on="ramp"/>', (26, "pose", "on"),
     ("'ramp' is tilted (roll 0.3, pitch 0 rad)", "roll = pitch = 0")),
    ("on itself", '<pose entity="can_0" on="can_0"/>', (26, "pose", "on"), ("cannot be put on itself",)),
    ("on a drawn entity", '<pose entity="can_0" on="box_1"/><pose entity="box_1" region="0 0 1 1"/>',
     (26, "pose", "on"), ("'box_1' is itself changed by <randomize>",)),
    ("region off the surface", '<pose entity="can_0" on="table_0" region="5 5 6 6"/>', (39, "pose", "region"),
     ("5 5 6 6 does not meet the top of 'table_0' (x -0.6 to 0.6, y -0.3 to 0.3)",)),
    ("z with on", '<pose entity="can_0" on="table_0" z="1"/>', (39, "pose", "z"), ("'z' with 'region' or 'area'",)),
    ("area without bounds", '<pose entity="can_0" area="spot"/>', (26, "pose", "area"),
     ("<named_pose> 'spot' has no 'bounds'", "valid: a named pose with bounds: zone")),
    ("unknown area", '<pose entity="can_0" area="nowhere"/>', (26, "pose", "area"),
     ("no <named_pose> 'nowhere'", "zone")),
    ("region and area", '<pose entity="can_0" area="zone" region="0 0 1 1"/>', (26, "pose", "area"),
     ("'region' and 'area' are both given",)),
    ("no place", '<pose entity="can_0"/>', (5, "pose", None),
     ("no place to draw from", "one of 'region' (x0 y0 x1 y1), 'on'", "'area'")),
    ("entity twice", '<pose entity="can_0" region="0 0 1 1"/><pose entity="can_0" region="0 0 1 1"/>',
     (50, "pose", "entity"), ("'can_0' is in a <pose> already (first on line 12)", "one <pose> per entity")),
    ("yaw lo > hi", '<pose entity="can_0" region="0 0 1 1" yaw="1 0"/>', (43, "pose", "yaw"),
     ("1 > 0 is an empty range",)),
    ("negative clearance", '<pose entity="can_0" region="0 0 1 1" clearance="-1"/>', (43, "pose", "clearance"),
     ("valid: 0 <= clearance <= 10 [m]",)),
    ("unknown attribute", '<pose entity="can_0" region="0 0 1 1" bogus="1"/>', (43, "pose", "bogus"),
     ("unknown attribute", "valid: area, clearance, entity, on, region, yaw, z")),
    ("entity without bounds", '<pose entity="ghost" region="0 0 1 1"/>', (11, "pose", "entity"),
     ("'ghost' has no bounds",)),
    ("choose a human", '<choose entity="man_0"><option color="1 0 0 1"/></choose>', (13, "choose", "entity"),
     ("'man_0' is a <human>", "valid: table_0, can_0, box_1, ghost, ramp")),
    ("choose twice", '<choose entity="can_0"><option/></choose><choose entity="can_0"><option/></choose>',
     (54, "choose", "entity"), ("'can_0' is in a <choose> already (first on line 12)",)),
    ("option typo", '<choose entity="can_0"><option colour="1 0 0 1"/></choose>', (36, "option", "colour"),
     ("did you mean 'color'?", "weight")),
    ("option renames", '<choose entity="can_0"><option name="x"/></choose>', (36, "option", "name"),
     ("an option cannot rename its object",)),
    ("option invalid as the object", '<choose entity="can_0"><option shape="sphere" size="0.1 0.2"/></choose>',
     (51, "option", "size"), ("expected 1 numbers for a sphere, got 2",)),
    ("option out of range", '<choose entity="can_0"><option mass="-1"/></choose>', (36, "option", "mass"),
     ("valid: 0 < mass <= 100000 [kg]",)),
    ("option weight", '<choose entity="can_0"><option weight="0"/></choose>', (36, "option", "weight"),
     ("valid: 0 < weight <= 1e+06",)),
    ("option missing file", '<choose entity="can_0"><option mesh="nofile.obj"/></choose>', (36, "option", "mesh"),
     ("file not found",)),
    ("no option", '<choose entity="can_0"></choose>', (5, "choose", None), ("<choose> holds no <option>",)),
    ("unknown element", "<spin/>", (5, "spin", None), ("unknown element inside <randomize>", "valid: pose, choose")),
]


@pytest.mark.parametrize(("line", "where", "says"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_is_reported_at_its_line_and_column(tmp_path: Path, line: str, where: tuple[int, str, str | None],
                                                      says: tuple[str, ...]) -> None:
    """Each bad <randomize> gives one issue when the file is read (no seed needed), at its line:column, saying what
    is wrong and what is valid."""
    (tmp_path / "novis.urdf").write_text('<robot name="n"><link name="a"/></robot>\n')
    path = _write(tmp_path, BASE.replace("LINE", line))
    with pytest.raises(WorldError) as info:
        parse_world(path)
    [issue] = info.value.issues
    assert (issue.file, issue.line, (issue.column, issue.element, issue.attribute)) == (path, 12, where), str(issue)
    for fragment in says:
        assert fragment in issue.message, f"{fragment!r} not in {issue.message!r}"


def test_randomize_twice_and_bad_seeds_are_refused(tmp_path: Path) -> None:
    """A second <randomize> is an error at its line; sample() refuses a negative or non-integer seed; the CLI exits
    2 on one, naming --seed and what is valid."""
    path = _write(tmp_path, '<world>\n  <randomize/>\n  <randomize/>\n</world>\n')
    with pytest.raises(WorldError) as info:
        parse_world(path)
    [issue] = info.value.issues
    assert (issue.line, issue.column) == (3, 3) and "may appear only once in a <world> (first on line 2)" in \
        issue.message
    world = parse_world(CLEANUP)
    for seed in (-1, 1.5, "3", True):
        with pytest.raises(SeedError, match="valid: an integer >= 0"):
            sample(world, seed)  # type: ignore[arg-type]
    plugins.load_plugins()
    for text in ("-1", "1.5", "abc", str(2**64)):
        r = CliRunner().invoke(app, ["check", str(CLEANUP), "--transport", "none", "--seed", text])
        assert r.exit_code == 2 and f"--seed '{text}': not a seed; valid: an integer 0 <= N" in r.stderr, r.output


# ------------------------------------------------------------------------------------------ <choose>


CHOOSE = f'''<world>
  <object name="table" urdf="{TABLE}" static="true"/>
  <object name="trash_3" shape="box" size="0.05 0.05 0.05" mass="0.1" pose="0 0 0.8" tags="trash" graspable="true"/>
  <object name="odd" shape="box" size="0.1 0.1 0.1" pose="3 3 0.05"/>
  <randomize>
    <pose entity="trash_3" on="table"/>
    <choose entity="trash_3">
      <option shape="cylinder" size="0.033 0.12" tags="trash can" color="0.8 0.1 0.1 1"/>
      <option shape="sphere" size="0.04" tags="trash burnable"/>
    </choose>
    <choose entity="odd">
      <option weight="1" color="1 0 0 1"/>
      <option weight="8" mesh="{MUG}" scale="0.5"/>
      <option weight="1" tags="plain"/>
    </choose>
  </randomize>
</world>
'''


def test_choose_picks_an_option_deterministically(tmp_path: Path) -> None:
    """Each seed picks an option, the same one every time; both options of trash_3 occur over 20 seeds; the picked
    attributes are in the world (the rest kept), and the pose on the table is the picked variant's (z = top + its
    half height); weights 1:8:1 make the middle option the most frequent; a mesh option replaces the box."""
    world = parse_world(_write(tmp_path, CHOOSE))
    seen = {}
    for seed in range(20):
        layout = draw(world, seed)
        assert layout.picks == draw(world, seed).picks
        pick = next(p for p in layout.picks if p.entity == "trash_3")
        trash = layout.world.agent("trash_3")
        assert isinstance(trash, Object) and (trash.mass, trash.graspable) == (0.1, True)
        if pick.option == 0:
            assert (trash.shape, trash.size, trash.tags, trash.color) == ("cylinder", (0.033, 0.12), ("trash", "can"),
                                                                          (0.8, 0.1, 0.1, 1.0))
            assert "color" in trash.model_fields_set and trash.pose.xyz[2] == pytest.approx(0.761)
        else:
            assert (trash.shape, trash.size, trash.tags) == ("sphere", (0.04,), ("trash", "burnable"))
            assert trash.pose.xyz[2] == pytest.approx(0.741)
        assert pick.line == 8 + pick.option
        seen[pick.option] = trash.tags
    assert set(seen) == {0, 1}
    counts = [0, 0, 0]
    for seed in range(200):
        layout = draw(world, seed)
        counts[next(p.option for p in layout.picks if p.entity == "odd")] += 1
        odd = layout.world.agent("odd")
        assert isinstance(odd, Object)
        if odd.mesh is not None:
            assert (odd.shape, odd.size, odd.scale, odd.mesh) == (None, None, 0.5, MUG)
    assert counts[1] > 4 * max(counts[0], counts[2]) and min(counts) > 0, counts


def test_the_models_reject_what_the_file_would(tmp_path: Path) -> None:
    """The <randomize> models are strict for Python users too: a <pose> needs a place, a <choose> an option."""
    with pytest.raises(ValueError, match="no place to draw from"):
        RandomPose(entity="a")
    with pytest.raises(ValueError, match="holds no <option>"):
        Choice(entity="a")
    spec = Randomize(poses=(RandomPose(entity="a", region="0 0 1 1"),),  # type: ignore[arg-type]
                     choices=(Choice(entity="b", options=(Option(),)),))
    assert spec.entities == ("b", "a") and spec.poses[0].region == (0.0, 0.0, 1.0, 1.0)


# ------------------------------------------------------------------------------------------ running it


@pytest.mark.slow
def test_a_seeded_run_keeps_the_trash_on_the_tables(world: World) -> None:
    """`sigcore run worlds/cleanup_random.xml --seed 3 --steps 200 --transport none` runs and says it drew; the same
    world run through the API for 200 steps leaves every item resting on its table where it was drawn."""
    r = sigcore("run", str(RANDOM), "--seed", "3", "--steps", "200", "--transport", "none", "-q")
    assert r.returncode == 0, r.stderr
    assert "drawn with seed 3" in r.stdout and "steps:    200" in r.stdout
    drawn = apply_seed(world, 3)
    sim = Simulation(drawn, "mujoco")
    run(sim, steps=200)
    final = sim.backend.get_poses([(name, None) for name in ITEMS])
    for (name, half), pose in zip(ITEMS.items(), final, strict=True):
        x, y, _ = _entity(drawn, name).pose.xyz
        assert abs(pose[2] - (0.70 + half)) < 2e-3, (name, pose[2])
        assert math.hypot(pose[0] - x, pose[1] - y) < 5e-3, (name, pose[:2], (x, y))


@pytest.mark.slow
def test_the_cli_says_what_the_seed_does(tmp_path: Path) -> None:
    """Without --seed a world with <randomize> runs as written and says so once; --seed on a world without it
    says it sets only the noise seed."""
    r = sigcore("run", str(RANDOM), "--steps", "1", "--transport", "none", "-q")
    assert r.returncode == 0 and r.stderr.count("--seed N draws them") == 1 and "drawn with" not in r.stdout
    assert "running it with the poses as written" in r.stderr
    plain = sigcore("run", str(CLEANUP), "--steps", "1", "--transport", "none", "-q", "--seed", "4")
    assert plain.returncode == 0 and "has no <randomize>: the seed only sets the seed of the sensor noise" in \
        plain.stderr
    assert sample(parse_world(CLEANUP), 4).agents == parse_world(CLEANUP).agents


@pytest.mark.slow
def test_a_seeded_recording_replays_bitwise(tmp_path: Path, world: World) -> None:
    """`run --seed 3 --record` stores the seed in the `sigcore` metadata; the recording's world (as `sigcore replay`
    and the viewer's playback rebuild it) is the drawn one, its ground truth starts at the drawn poses, and
    `sigcore replay` reproduces the end bit for bit; the world as written does not (the comparison can fail)."""
    from sigcore.record.reader import open_recording
    from sigcore.record.replay import Replayer, compare, load_recording, poses_now

    bag = tmp_path / "bag"
    r = sigcore("run", str(RANDOM), "--seed", "3", "--steps", "300", "--transport", "none", "--record", str(bag),
                "-q")
    assert r.returncode == 0, r.stderr
    rec = load_recording(bag)
    assert (rec.facts["seed"], rec.facts["noise_seed"], rec.seed) == ("3", "3", 3)
    drawn = apply_seed(world, 3)
    assert rec.world(tmp_path / "w").model_dump() == drawn.model_dump()
    viewer = open_recording(bag)  # as the viewer's playback opens it
    assert viewer.world(tmp_path / "v").model_dump() == drawn.model_dump()
    step, start = rec.truth[0]
    assert step == 0 and np.allclose(start["ground_truth/can_0"][:3], _entity(drawn, "can_0").pose.xyz)
    replay = sigcore("replay", str(bag), "-q")
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert "drawn with seed 3" in replay.stdout and re.search(r"ground truth at step 300: \d+ frames, bitwise equal",
                                                              replay.stdout), replay.stdout
    sim = Simulation(parse_world(RANDOM), "mujoco", rec.controllers)
    run(sim, steps=rec.final_step, transport=[Replayer(rec.inputs)])
    equal, worst, _ = compare(rec.truth[-1][1], poses_now(sim))
    assert not equal and worst > 0.01


def test_an_unseeded_recording_records_no_seed(tmp_path: Path) -> None:
    """A run without --seed records an empty seed and the file's noise seed: the replay builds the world as
    written."""
    from sigcore.record import Recorder
    from sigcore.record.replay import load_recording

    sim = Simulation(parse_world(RANDOM), "mujoco")
    recorder = Recorder(sim, tmp_path / "bag")
    run(sim, steps=5)
    recorder.close()
    rec = load_recording(tmp_path / "bag")
    assert (rec.facts["seed"], rec.facts["noise_seed"], rec.seed) == ("", "0", None)
    assert rec.world(tmp_path / "w").model_dump() == parse_world(RANDOM).model_dump()


# ------------------------------------------------------------------------------------------ the reference


def _table(title: str) -> dict[str, list[str]]:
    """The rows of the attribute table under the heading starting with ``title`` in docs/world-format.md."""
    text = DOCS.read_text(encoding="utf-8")
    section = re.search(rf"^#+ {re.escape(title)}.*?(?=^#)", text, re.M | re.S)
    assert section is not None, title
    rows = [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in section.group(0).splitlines() if line.startswith("| `")]
    return {row[0].split()[0].strip("`"): row for row in rows}


def test_the_reference_lists_every_attribute() -> None:
    """docs/world-format.md documents each attribute of <randomize>, <pose>, <choose> and <option> with its
    default, and the structure names <randomize>."""
    internal = {"line", "column", "positions", "poses", "choices", "options", "attributes"}
    for title, models in (("`<randomize>`", [Randomize]), ("`<pose>` (in", [RandomPose]),
                          ("`<choose>` (in", [Choice, Option])):
        rows = _table(title)
        fields = {name: field for model in models for name, field in model.model_fields.items()
                  if name not in internal}
        assert set(rows) == set(fields), title
        for name, row in rows.items():
            field = fields[name]
            default = "required" if field.is_required() else "none" if field.default is None else f"{field.default:g}"
            assert row[3] == f"`{default}`", (title, name)
    assert "<randomize ...>" in DOCS.read_text(encoding="utf-8")
