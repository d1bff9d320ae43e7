"""The run control's verbs (``sigcore.sim.control.RunControl``, issue 29 item 3): one meaning of play, pause, step,
reset, pace and stop for every client; read-only state; refusals that say what is valid; a ``control`` event per
verb. (The viewer and simulation_interfaces driving it alike: ``tests/ros2/test_run_control_alike.py``.)"""

from __future__ import annotations

import math

import pytest

from sigcore.sim import ControlChange, RunControl, RunStateError, Simulation, run


def test_play_pause_and_step_mean_one_thing() -> None:
    """step(n) pauses and adds n pending steps; the loop takes them one by one; play and pause drop what is
    pending."""
    c = RunControl()
    assert (c.paused, c.pending_steps, c.idle) == (False, 0, False) and c.take_step()
    c.step(3)
    c.step(2)
    assert (c.paused, c.pending_steps) == (True, 5)
    assert [c.take_step() for _ in range(7)] == [True] * 5 + [False] * 2 and c.idle
    c.step(4)
    c.play()
    assert (c.paused, c.pending_steps) == (False, 0)
    c.step(4)
    c.pause()
    assert (c.paused, c.pending_steps, c.idle) == (True, 0, True)
    c.step(4)
    c.drop_steps(3)
    assert c.pending_steps == 1
    c.drop_steps(10)
    assert c.pending_steps == 0


def test_state_is_read_only() -> None:
    c = RunControl()
    for name in ("paused", "pending_steps", "stopping", "stop_reason", "realtime_factor"):
        with pytest.raises(AttributeError):
            setattr(c, name, 1)


@pytest.mark.parametrize("bad", [0, -1, 2.5, "10", True, None])
def test_bad_step_counts_are_refused_and_change_nothing(bad: object) -> None:
    c = RunControl()
    with pytest.raises(RunStateError, match=r"steps must be a whole number of at least 1, got "):
        c.step(bad)  # type: ignore[arg-type]
    assert (c.paused, c.pending_steps) == (False, 0)


@pytest.mark.parametrize("bad", [0, -2.0, math.nan, math.inf, "2", True])
def test_bad_paces_are_refused_and_change_nothing(bad: object) -> None:
    c = RunControl(realtime_factor=1.0)
    with pytest.raises(RunStateError, match=r"positive number .* or None \(as fast as possible\)"):
        c.set_pace(bad)  # type: ignore[arg-type]
    assert c.realtime_factor == 1.0
    c.set_pace(None)
    assert c.realtime_factor is None


def test_stop_keeps_the_first_reason_and_rearm_forgets_it() -> None:
    c = RunControl()
    c.stop("SIGINT")
    c.stop("SIGTERM")
    assert (c.stopping, c.stop_reason) == (True, "SIGINT")
    c.rearm()
    assert (c.stopping, c.stop_reason) == (False, None)


def test_without_a_world_play_step_and_reset_are_refused_naming_load_world(sim: Simulation) -> None:
    """No world loaded: play, step and reset are refused with a message saying to load one; pause is allowed."""
    sim.worlds.unload()
    c = sim.control
    for verb, call in (("play", c.play), ("step", lambda: c.step(1)), ("reset", c.request_reset)):
        with pytest.raises(RunStateError, match=rf"no world is loaded: nothing to {verb}; load one first"):
            call()
    c.pause()
    assert c.idle


def test_reset_is_done_at_once_and_keeps_the_run_state(sim: Simulation) -> None:
    """request_reset restores the world now (the ball back where it started), keeps paused, pending steps and pace,
    and time goes on."""
    start = sim.backend.get_pose("ball")[0].copy()
    sim.entities["ball"].set_position([0.5, 0.5, 1.0])
    sim.step(10)
    c = sim.control
    c.set_pace(2.0)
    c.step(7)
    c.request_reset()
    assert (c.paused, c.pending_steps, c.realtime_factor) == (True, 7, 2.0)
    assert sim.step_count == 10
    assert sim.backend.get_pose("ball")[0] == pytest.approx(start, abs=1e-9)


def test_each_verb_is_a_control_event_with_the_step_count(sim: Simulation) -> None:
    """Every verb emits one ``control`` event with the state after it and the step it was done at; the loop's own
    bookkeeping emits none."""
    seen: list[ControlChange] = []
    sim.events.subscribe("control", seen.append)
    c = sim.control
    c.pause()
    c.step(3)
    while c.take_step():
        sim.step()
    c.set_pace(None)
    c.request_reset(despawn=False)
    c.play()
    c.stop("request")
    assert [(e.verb, e.paused, e.pending_steps, e.stopping, e.step) for e in seen] == [
        ("pause", True, 0, False, 0), ("step", True, 3, False, 0), ("pace", True, 0, False, 3),
        ("reset", True, 0, False, 3), ("play", False, 0, False, 3), ("stop", False, 0, True, 3)]


def test_a_run_ends_on_stop_with_its_reason(sim: Simulation) -> None:
    """``run`` takes steps while the control allows; a stop from a step subscriber ends it with the reason."""
    def stop_at_20(s: Simulation) -> None:
        if s.step_count == 20:
            s.control.stop("enough")

    sim.events.subscribe("step", stop_at_20)
    report = run(sim, steps=100, handle_signals=False)
    assert (report.steps, report.stopped_by) == (20, "enough")
