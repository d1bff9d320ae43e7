"""MuJoCo's compiled stepping loop (``sigcore_backend_mujoco.steps``): the same run, bit for bit, as stepping one
step at a time in Python; batches only where nothing is due; a clear fallback when it cannot be built."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sigcore_backend_mujoco import steps
from sigcore_backend_mujoco.backend import MujocoBackend

from sigcore.agent.events import CollisionEvent
from sigcore.sim import Simulation, run
from sigcore.sim.batching import BATCH_STEPS
from sigcore.world import parse_world

CLEANUP = Path(__file__).resolve().parents[2] / "worlds" / "cleanup.xml"


class Batches(MujocoBackend):
    """The real backend, counting the steps each ``step_batch`` call took."""

    def __init__(self) -> None:
        super().__init__()
        self.taken: list[int] = []

    def step_batch(self, n: int, contacts: bool) -> int:
        k = super().step_batch(n, contacts)
        self.taken.append(k)
        return k


@pytest.fixture
def python_steps(monkeypatch: pytest.MonkeyPatch):
    """Within the test, simulations built from now on step one step at a time in Python."""
    monkeypatch.setenv(steps.ENV, "0")
    steps.compiled.cache_clear()
    yield
    monkeypatch.delenv(steps.ENV)
    steps.compiled.cache_clear()


def _session(sim: Simulation, single: bool = False) -> dict[str, Any]:
    """Drive the clean-up world through contacts that change (an apple lifted and dropped, the robot driving), a
    held entity released, a one-step force and arm targets; returns everything observable."""
    events: list[CollisionEvent] = []
    scans: list[tuple[float, bytes]] = []
    sim.events.subscribe("collision", events.append)
    sim.events.subscribe("scan", lambda s: scans.append((s.stamp, np.asarray(s.ranges).tobytes())))

    states: list[tuple[bytes, bytes, frozenset[tuple[str, str, str]]]] = []

    def step(n: int) -> None:
        if single:
            for _ in range(n):
                sim.step()
        else:
            sim.step(n)
        data = sim.backend.data  # type: ignore[attr-defined]
        states.append((data.qpos.tobytes(), data.qvel.tobytes(), sim.contact_triples()))

    step(300)
    sim.robot("robot_000").set_base_velocity(0.4, 0.5)
    step(700)
    apple = sim.agent("apple_2")
    apple.set_position(apple.position() + np.array([0.0, 0.0, 0.25]))
    step(400)
    apple.add_force(np.array([0.0, -3.0, 2.0]))
    can = sim.agent("can_0")
    can.set_dynamics_mode(False)
    can.set_position(can.position() + np.array([0.0, 0.0, 0.05]))
    step(600)
    can.set_dynamics_mode(True)
    robot = sim.robot("robot_000")
    robot.set_joint_target("r_finger_2_joint", 0.03)
    step(1000)
    return {"states": states, "time": sim.time, "steps": sim.step_count,
            "events": [(e.agent, e.part, e.other, e.time) for e in events], "scans": scans}


def test_the_compiled_loop_is_built_here() -> None:
    """On this machine (a C compiler, the mujoco wheel's headers) the backend steps through the compiled loop."""
    assert steps.compiled() is not None, steps.status()
    assert steps.status().startswith("compiled stepping loop: ")


def test_batched_steps_equal_single_python_steps_bit_for_bit(python_steps) -> None:
    """The clean-up world driven through changing contacts, a held entity, a force and arm targets: stepping one
    step at a time in Python and batching steps in the compiled loop end in the same state to the bit, with the
    same contact events at the same times and the same scans; the compiled run took most steps in batches."""
    world = parse_world(CLEANUP)
    python = _session(Simulation(world, "mujoco"), single=True)
    steps.compiled.cache_clear()
    with pytest.MonkeyPatch.context() as mp:
        mp.delenv(steps.ENV)
        backend = Batches()
        sim = Simulation(world, backend)
        assert backend._loop is not None
        batched = _session(sim)
    assert python["events"], "the session must produce contact events to compare"
    assert len(python["scans"]) >= 10
    for key in python:
        assert batched[key] == python[key], key
    assert sum(k for k in backend.taken if k > 1) > 0.5 * sum(backend.taken)  # most steps batched
    assert max(backend.taken) <= BATCH_STEPS


def test_python_fallback_is_said_and_used(python_steps) -> None:
    """With SIGCORE_COMPILED_STEPS=0 the backend steps in Python, and status() says why."""
    sim = Simulation(parse_world(CLEANUP), "mujoco")
    assert sim.backend._loop is None  # type: ignore[attr-defined]
    assert steps.status() == f"stepping in Python: {steps.ENV}=0"
    sim.step(100)
    assert sim.step_count == 100


def test_a_compiler_that_fails_leaves_python_stepping_with_its_message(tmp_path: Path) -> None:
    """A fresh cache and a 'compiler' that fails (``false``): the library is not built, the backend steps in
    Python, and status() names what failed; with the real compiler the same fresh cache gets the library."""
    code = ("from sigcore_backend_mujoco import steps; from sigcore.sim import Simulation; "
            f"from sigcore.world import parse_world; sim = Simulation(parse_world({str(CLEANUP)!r}), 'mujoco'); "
            "sim.step(50); print(sim.step_count); print(steps.status())")
    env = {"XDG_CACHE_HOME": str(tmp_path / "cache"), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    failed = subprocess.run([sys.executable, "-c", code], env={**env, "CC": "false"}, capture_output=True,
                            text=True, timeout=120)
    assert failed.returncode == 0, failed.stderr
    count, status = failed.stdout.strip().splitlines()[-2:]
    assert count == "50"
    assert status.startswith("stepping in Python: compiling _steps.c with /usr/bin/false failed"), status
    assert not list((tmp_path / "cache" / "sigcore").glob("*.so*"))  # nothing half-written left behind
    built = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert built.returncode == 0, built.stderr
    assert built.stdout.strip().splitlines()[-1].startswith(f"compiled stepping loop: {tmp_path / 'cache'}")
    assert len(list((tmp_path / "cache" / "sigcore").glob("steps-*.so"))) == 1


def test_a_step_subscriber_of_every_step_gets_every_step() -> None:
    """A step subscriber without ``every`` is called after every step (no step is batched past it); one with
    ``every=7`` after the multiples of 7 only, and batches run between them."""
    backend = Batches()
    sim = Simulation(parse_world(CLEANUP), backend)
    seen: list[int] = []
    sub = sim.events.subscribe("step", lambda s: seen.append(s.step_count))
    sim.step(50)
    assert seen == list(range(1, 51)) and set(backend.taken) <= {1}
    sub.cancel()
    seen.clear()
    backend.taken.clear()
    sim.events.subscribe("step", lambda s: seen.append(s.step_count), every=7)
    sim.step(100)
    assert seen == [s for s in range(51, 151) if s % 7 == 0]
    assert max(backend.taken) > 1


def test_the_run_loop_stops_at_the_step_a_stop_was_asked_in_a_batch() -> None:
    """Without a transport the run loop hands out batches; a feature that asks to stop at step 370 (its subscriber
    runs every 37 steps) ends the run after exactly that step, as single steps would."""
    sim = Simulation(parse_world(CLEANUP), "mujoco")

    def maybe_stop(s: Simulation) -> None:
        if s.step_count == 370:
            s.control.stop("request")

    sim.events.subscribe("step", maybe_stop, every=37)
    report = run(sim, steps=5000)
    assert report.steps == 370 and sim.step_count == 370
    assert report.stopped_by == "request"


TILES = ('<object name="tile_a" shape="box" size="0.4 0.4 0.1" pose="0 0 0.05" static="true"/>'
         '<object name="tile_b" shape="box" size="0.4 0.4 0.1" pose="0.4 0 0.05" static="true"/>'
         '<object name="ball" shape="sphere" size="0.05" pose="0 0 0.15"/>')


def test_a_ball_rolling_across_tiles_starts_its_episodes_at_the_same_steps_in_batches(make_world) -> None:
    """A ball rolls from one tile onto the next and off onto the floor within one call of 600 steps: the compiled
    loop stops after each step whose contacts changed, so every episode starts at the same step and time as with
    single steps, and the steps between were batched."""
    def roll(sim: Simulation, single: bool) -> list[tuple[str, str, str, float]]:
        events: list[CollisionEvent] = []
        sim.events.subscribe("collision", events.append)
        sim.step(50)
        sim.agent("ball").set_velocity(np.array([1.0, 0.0, 0.0]))
        for _ in range(600 if single else 1):
            sim.step(1 if single else 600)
        return [(e.agent, e.part, e.other, e.time) for e in events]

    world = make_world(TILES)
    backend = Batches()
    batched = roll(Simulation(world, backend), single=False)
    single = roll(Simulation(world, "mujoco"), single=True)
    assert [e[2] for e in single if e[0] == "ball"][:2] == ["tile_a", "tile_b"]
    assert batched == single
    assert max(backend.taken) > 50
